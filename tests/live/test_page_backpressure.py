"""Back-pressure of the live page (:class:`fsrlab.live.page.Updater`): a tab's browser acknowledges the updates it
has applied, and no more than :data:`~fsrlab.live.page.BEHIND_S` of updates go out ahead of it.

References: the documented rule (docs/live.md, "Rates"), counted with a session that reads one window per call and
acknowledgements the test gives; a real browser, whose page must send the acknowledgements back.
"""

from __future__ import annotations

import math
import time
from types import SimpleNamespace

import pytest

from browser import LiveServer, chromium, text
from fsrlab.live import page
from fsrlab.live.page import BEHIND_S, POINTS, Updater, WindowPlots


class _Plots:
    def __init__(self):
        self.added, self.flushes = [], 0

    def add(self, cols):
        self.added.extend(cols["seq"])

    def flush(self):
        self.flushes += 1

    def refresh(self):
        pass


def _updater(monkeypatch, refresh_s=0.04):
    clock = [1000.0]
    monkeypatch.setattr(page.time, "monotonic", lambda: clock[0])
    seq = [0]

    def since(cursor):  # one new window per call, numbered
        seq[0] += 1
        return cursor + 1, {"seq": [seq[0]], "frequency_hz": [1e3], "duty_cycle": [0.5], "voltage_v": [1.0],
                            "reference": [0.0]}

    plots = _Plots()
    update = Updater(SimpleNamespace(since=since, estimator=None), plots, _Plots(), "force", "N", 1.0, refresh_s)

    def call(n=1):
        for _ in range(n):
            update()
            clock[0] += refresh_s
    return update, plots, call


def _shown(update) -> int:
    return int(update.latest.text.split("<span id='latest-seq'>")[1].split("<")[0])


def test_a_tab_that_stops_acknowledging_is_sent_at_most_behind_s_of_updates(monkeypatch):
    update, plots, call = _updater(monkeypatch)
    ahead = math.ceil(BEHIND_S / 0.04)  # 25 updates of 40 ms
    call()
    update.ack.tags = [1]  # the browser applied the first update (as its page's callback answers)
    assert update.acked == 1
    call(100)
    assert update.sent == 1 + ahead and update.latest.tags == [update.sent] and _shown(update) == update.sent
    flushes = plots.flushes
    call(50)  # held back: nothing more goes out, every window still reaches the plots' queue
    assert update.sent == 1 + ahead and plots.flushes == flushes and plots.added == list(range(1, 152))
    update.ack.tags = [update.sent]  # the browser caught up: the latest window is shown, the plots flushed
    call()
    assert _shown(update) == 152 and update.sent == 2 + ahead and plots.flushes == flushes + 1


def test_a_browser_that_never_acknowledges_is_updated_as_if_it_kept_up(monkeypatch):
    update, _, call = _updater(monkeypatch)
    call(200)
    assert update.acked is None and update.sent == 200 and _shown(update) == 200


@pytest.mark.parametrize("value", [[], ["5"], [-1], [10_000], [1.5], "x"])
def test_an_acknowledgement_that_is_no_count_sent_is_ignored(monkeypatch, value):
    update, _, call = _updater(monkeypatch)
    call(3)
    update._acknowledged("tags", [], value)
    assert update.acked is None


def test_at_the_slowest_refresh_two_updates_may_be_out(monkeypatch):
    """BEHIND_S of 10 s updates is less than one: at least two go out, so one in flight never stops the next."""
    update, _, call = _updater(monkeypatch, refresh_s=10.0)
    call()
    update.ack.tags = [1]
    call(5)
    assert update.sent == 3 and _shown(update) == 3


def test_the_plots_queue_of_a_held_tab_keeps_only_what_the_plot_shows():
    plots = WindowPlots(SimpleNamespace(estimator=None), "force", "N", 1.0)
    n = POINTS + 500
    cols = {"time_s": [0.0] * n, "seq": list(range(n)), "frequency_hz": [1e3] * n, "duty_cycle": [0.5] * n,
            "voltage_v": [1.0] * n, "reference": [0.0] * n, "estimate": [0.0] * n, "uncertainty": [0.0] * n}
    plots.add(cols)
    assert plots.pending["seq"] == list(range(500, n)) and all(len(v) == POINTS for v in plots.pending.values())


def test_a_real_browser_acknowledges_the_updates_it_applies():
    """The page's callback copies each update's count into the hidden ack model, whose change Bokeh sends back
    to the server: read in the browser, the ack follows the count shown (within what is in flight)."""
    driver = chromium()
    server = LiveServer("--virtual", "--seed", "4", "--window", "20ms", "--refresh", "250ms")
    try:
        driver.get(server.url)
        script = ("const d = Bokeh.documents[0]; if (!d) return null; const l = d.get_model_by_name('latest'), "
                  "a = d.get_model_by_name('ack'); return [l.tags[0], a.tags.length ? a.tags[0] : null];")
        seen = None
        deadline = time.monotonic() + 180
        while time.monotonic() < deadline:
            seen = driver.execute_script(script)
            if seen and seen[1] is not None and seen[1] >= 5 and text(driver, "#latest-seq") is not None:
                break
            time.sleep(0.1)
    finally:
        server.stop()
        driver.quit()
    assert seen is not None and seen[1] is not None and 5 <= seen[1] <= seen[0], seen
