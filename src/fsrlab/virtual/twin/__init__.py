"""The digital twin of the fsrlab meter: the real firmware in simavr, driven by the physics, on a pty.

- :mod:`~fsrlab.virtual.twin.edges`: the LM555's output edges from the exact transient, streamed in chunks,
  with the C_off switch the firmware drives.
- :mod:`~fsrlab.virtual.twin.process`: the harness binary (``make firmware``), :func:`twin_available`, the
  records it reads.
- :mod:`~fsrlab.virtual.twin.twin`: :class:`Twin` (pty, harness process, feeder and reader threads).

docs/twin.md describes the design.
"""

from fsrlab.virtual.twin.process import twin_available
from fsrlab.virtual.twin.twin import Twin

__all__ = ["Twin", "twin_available"]
