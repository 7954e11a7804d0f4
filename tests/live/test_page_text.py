"""What the live page shows inside its HTML passes the one rendering boundary and is markup-escaped.

Reference: properties that must hold: no control character reaches the page raw (issue 40: the live page's
log is printed text too), and a file name or message holding markup is shown as text, not run as HTML.
"""

import re

from fsrlab.live.page import _html


def test_control_characters_and_markup_are_shown_as_text():
    shown = _html("run\x1b[2J<img src=x onerror=alert(1)>&\u202e.csv")
    assert not re.search(r"[\x00-\x08\x0b-\x1f\x7f\u202e]", shown)
    assert "<" not in shown and ">" not in shown
    assert shown == r"run\x1b[2J&lt;img src=x onerror=alert(1)&gt;&amp;\u202e.csv"


def test_plain_text_is_unchanged():
    assert _html("recording into /tmp/run-1.csv: 120 rows, 0.5 s") == "recording into /tmp/run-1.csv: 120 rows, 0.5 s"
    assert _html(3) == "3"
