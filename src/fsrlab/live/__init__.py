"""``fsrlab live``: the meter's front panel in a browser (Bokeh server; session, page, server)."""
