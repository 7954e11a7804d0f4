"""Files: runs (schema, cells, reading, crash-safe writing), the small CSV tables, calibration files, JSON
output, and foreign CSV files (a user's own sketch or logger) made into runs.

Reading and writing only; the computations that use the files live in the layers above.
"""
