"""Results as JSON: numpy values, paths and nested containers made of JSON types.

Used for every ``--json`` output of the command line and for the numbers a report writes
(``report.json``), so both spell a value the same way.
"""

from __future__ import annotations

import math
import sys
from typing import Any

__all__ = ["to_jsonable"]


def to_jsonable(obj: Any) -> Any:
    """Convert numpy scalars and arrays, paths and nested containers to JSON types.

    Parameters
    ----------
    obj : object
        Nested dicts, lists, numpy values.

    Returns
    -------
    object
        The same structure made of JSON types; non-finite floats become ``None``.
    """
    if isinstance(obj, dict):
        return {str(k): to_jsonable(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [to_jsonable(v) for v in obj]
    np = sys.modules.get("numpy")  # a numpy value exists only once numpy is imported: no import here
    if np is not None and isinstance(obj, np.ndarray):
        return to_jsonable(obj.tolist())
    if np is not None and isinstance(obj, np.generic):
        return to_jsonable(obj.item())
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if hasattr(obj, "__fspath__"):
        return str(obj)
    return obj
