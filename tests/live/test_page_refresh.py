"""The live page's refresh period (``fsrlab live --refresh``, :func:`fsrlab.live.page.check_refresh`).

References: the documented range (40 ms to 10 s, docs/live.md), the rule that the plots redraw at most every
``max(refresh, PLOT_S)`` (counted with a clock the test sets), and a real browser counting how often the page's
numbers change.
"""

from __future__ import annotations

import time
from types import SimpleNamespace

import pytest

from browser import LiveServer, chromium, text
from clirun import run_cli
from fsrlab.errors import ParameterError
from fsrlab.live import page
from fsrlab.live.page import PLOT_S, REFRESH_MAX_S, STATUS_S, UPDATE_S, Updater, check_refresh


@pytest.mark.parametrize("value", [0.0, 0.039, -1.0, 10.5, float("nan"), float("inf")])
def test_a_refresh_outside_40_ms_to_10_s_is_refused_naming_it(value):
    with pytest.raises(ParameterError) as err:
        check_refresh(value)
    assert err.value.parameter == "refresh_s"


@pytest.mark.parametrize("value", ["1s", None])
def test_a_refresh_that_is_no_number_is_a_type_error_naming_it(value):
    with pytest.raises(TypeError, match="^refresh_s: "):
        check_refresh(value)


@pytest.mark.parametrize("value", [UPDATE_S, 0.25, 1, REFRESH_MAX_S])
def test_a_refresh_in_range_is_taken(value):
    assert check_refresh(value) == float(value)


def test_the_command_refuses_a_bad_refresh_in_one_line_before_serving():
    code, _, err = run_cli(["live", "--virtual", "--refresh", "10ms"])
    assert code == 2 and err.count("\n") == 1 and err.startswith("fsrlab: error: Invalid value for --refresh: ")


class _Counter:
    def __init__(self):
        self.flushes = self.refreshes = 0

    def add(self, cols):
        pass

    def flush(self):
        self.flushes += 1

    def refresh(self):
        self.refreshes += 1


def _redraws(refresh_s: float, seconds: float, monkeypatch) -> tuple[int, int]:
    """Redraws of the plots and of the status lines over ``seconds`` of calls every ``refresh_s`` (the clock set
    by the test)."""
    clock = [1000.0]
    monkeypatch.setattr(page.time, "monotonic", lambda: clock[0])
    row = {"seq": [1], "frequency_hz": [1e3], "duty_cycle": [0.5], "voltage_v": [1.0], "reference": [0.0]}
    session = SimpleNamespace(since=lambda cursor: (cursor + 1, row), estimator=None)
    plots = _Counter()
    update = Updater(session, plots, _Counter(), "force", "N", 1.0, refresh_s)
    for _ in range(round(seconds / refresh_s)):
        update()
        clock[0] += refresh_s
    return plots.flushes, plots.refreshes


def test_plots_redraw_at_most_every_plot_s_and_every_call_when_calls_are_slower(monkeypatch):
    # calls every 40 ms: plots when 100 ms have passed (every third call, 120 ms), status lines when 250 ms
    # have (every seventh, 280 ms), over 12 s
    plots, status = _redraws(UPDATE_S, 12.0, monkeypatch)
    assert plots == pytest.approx(12.0 / 0.12, abs=1) and status == pytest.approx(12.0 / 0.28, abs=1)
    # calls every 250 ms (PLOT_S and STATUS_S or more apart): every call redraws both, none lost to the clock
    assert PLOT_S <= 0.25 and STATUS_S <= 0.25 and _redraws(0.25, 12.0, monkeypatch) == (48, 48)


def test_a_slower_refresh_shows_every_250_ms_of_windows_in_the_browser():
    """A real page at 20 ms windows with --refresh 250ms: between two numbers the page shows, about 12.5 windows
    (250 ms / 20 ms) were read; the median step of the window number shown must be at least 8 (the default
    40 ms shows every second window). The step is counted in the device's windows, so a page that lags on a
    busy machine and applies its updates late does not change it."""
    import statistics

    driver = chromium()
    server = LiveServer("--virtual", "--seed", "4", "--window", "20ms", "--refresh", "250ms")
    try:
        driver.get(server.url)
        shown: list[int] = []
        deadline = time.monotonic() + 180
        while len(shown) < 12 and time.monotonic() < deadline:
            now = text(driver, "#latest-seq")
            if now is not None and (not shown or int(now) != shown[-1]):
                shown.append(int(now))
            time.sleep(0.02)
    finally:
        server.stop()
        driver.quit()
    assert len(shown) >= 12, shown
    steps = [b - a for a, b in zip(shown[1:], shown[2:], strict=False)]  # the first may be a partial step
    assert statistics.median(steps) >= 8, steps
