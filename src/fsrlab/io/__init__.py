"""Files: runs (schema, cells, reading, crash-safe writing), the small CSV tables, calibration files, JSON output.

Reading and writing only; the computations that use the files live in the layers above.
"""
