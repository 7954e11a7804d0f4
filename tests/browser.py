"""A real headless Chromium for the browser tests (Debian's chromium and chromium-driver, no download).

Bokeh renders its widgets inside shadow roots, so the helpers search the DOM through them.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path

from toolcheck import require_file

CHROMIUM = "/usr/bin/chromium"
CHROMEDRIVER = "/usr/bin/chromedriver"
ARTIFACTS = Path(__file__).resolve().parents[1] / "build" / "test-artifacts"
#: How long a script call or a page load may take before the test fails (a guard against a hang). [s]
SCRIPT_TIMEOUT_S = 300.0
#: How long :func:`wait_for` waits by default (a guard against a hang, not a speed requirement). [s]
WAIT_S = 180.0
#: ``fsrlab live`` options for a page that keeps up on a busy machine: at the default 40 ms the page took 1.1
#: cores of this 2-core machine, and with one other busy process it fell minutes behind (docs/live.md, Rates).
#: The tests that do not measure the rate use it; tests/live/test_page_refresh.py checks the rate itself.
LIGHT = ("--refresh", "250ms")

# Find the first element matching a CSS selector in the document or any shadow root below it.
FIND_JS = """
function walk(root, sel) {
  const el = root.querySelector ? root.querySelector(sel) : null;
  if (el) return el;
  for (const n of (root.querySelectorAll ? root.querySelectorAll('*') : [])) {
    if (n.shadowRoot) { const r = walk(n.shadowRoot, sel); if (r) return r; }
  }
  return null;
}
"""


def chromium(width: int = 1400, height: int = 1000):
    """A headless Chromium WebDriver (skips, or fails with CI=true, without Debian's chromium)."""
    require_file(CHROMIUM, "Debian's chromium")
    require_file(CHROMEDRIVER, "Debian's chromium-driver")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                f"--window-size={width},{height}"):
        opts.add_argument(arg)
    driver = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    # A guard, not a limit: a script call waits for the page's main thread, which a loaded machine can keep
    # busy for tens of seconds (Selenium's default of 30 s failed a run under load; docs/live.md, Rates).
    driver.set_script_timeout(SCRIPT_TIMEOUT_S)
    driver.set_page_load_timeout(SCRIPT_TIMEOUT_S)
    return driver


def text(driver, selector: str) -> str | None:
    """Text of the first element matching ``selector`` (shadow roots included), or None.

    The root an element was found in is remembered in the page, so later look-ups are quick.
    """
    return driver.execute_script(FIND_JS + """
      const sel = arguments[0];
      window.__fsrlabRoots = window.__fsrlabRoots || [];
      for (const r of window.__fsrlabRoots) { const e = r.querySelector(sel); if (e) return e.textContent; }
      const e = walk(document, sel);
      if (!e) return null;
      window.__fsrlabRoots.push(e.getRootNode());
      return e.textContent;""", selector)


def texts(driver, selectors) -> dict:
    """Texts of several elements read in one step (one page state), by :func:`text`'s rules."""
    return driver.execute_script(FIND_JS + """
      const out = {};
      window.__fsrlabRoots = window.__fsrlabRoots || [];
      for (const sel of arguments[0]) {
        let found = null;
        for (const r of window.__fsrlabRoots) { const e = r.querySelector(sel); if (e) { found = e; break; } }
        if (!found) { found = walk(document, sel); if (found) window.__fsrlabRoots.push(found.getRootNode()); }
        out[sel] = found ? found.textContent : null;
      }
      return out;""", list(selectors))


# Every button whose text is arguments[0], in the document and every shadow root.
_BUTTONS_JS = """
function buttons(root, want, out) {
  for (const n of (root.querySelectorAll ? root.querySelectorAll('*') : [])) {
    if (n.tagName === 'BUTTON' && n.textContent.trim() === want) out.push(n);
    if (n.shadowRoot) buttons(n.shadowRoot, want, out);
  }
  return out;
}
const b = buttons(document, arguments[0], [])[0];
"""


def click_button(driver, label: str) -> bool:
    """Click the button whose text is ``label``; False when there is none."""
    return driver.execute_script(_BUTTONS_JS + "if (!b) return false; b.click(); return true;", label)


def button_disabled(driver, label: str) -> bool | None:
    """Whether the button with text ``label`` is disabled (None: no such button)."""
    return driver.execute_script(_BUTTONS_JS + "return b ? b.disabled : null;", label)


def model_length(driver, name: str, column: str) -> int:
    """Length of a column of the named ColumnDataSource as BokehJS holds it in the page."""
    return driver.execute_script("""
      const doc = Bokeh.documents[0];
      const src = doc.get_model_by_name(arguments[0]);
      const d = src.data;
      const col = (d instanceof Map) ? d.get(arguments[1]) : d[arguments[1]];
      return col.length;""", name, column)


def wait_for(fn, timeout_s: float = WAIT_S, interval_s: float = 0.1):
    """Call ``fn`` until it returns a truthy value; that value, or the last one at the timeout."""
    deadline = time.monotonic() + timeout_s
    value = fn()
    while not value and time.monotonic() < deadline:
        time.sleep(interval_s)
        value = fn()
    return value


class LiveServer:
    """``fsrlab live`` in a subprocess with ``--json``: its URL from the first line."""

    def __init__(self, *args: str, timeout_s: float = 30.0) -> None:
        exe = str(Path(sys.executable).with_name("fsrlab"))
        import signal

        # Ctrl-C restored in the child (stop() sends it): a runner started in the background passes it on ignored.
        self.proc = subprocess.Popen([exe, "live", "--http-port", "0", "--json", *args], stdout=subprocess.PIPE,
                                     stderr=subprocess.PIPE, text=True, env={**os.environ, "PYTHONUNBUFFERED": "1"},
                                     preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        line = self.proc.stdout.readline()
        if not line:
            raise RuntimeError(f"fsrlab live ended: {self.proc.stderr.read()}")
        self.info = json.loads(line)
        self.url = self.info["url"]

    def stop(self) -> tuple[dict | None, str]:
        """Interrupt the server (Ctrl-C) and return its closing JSON line and stderr."""
        import signal

        if self.proc.poll() is None:
            self.proc.send_signal(signal.SIGINT)
        try:
            out, err = self.proc.communicate(timeout=15)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            out, err = self.proc.communicate()
        last = [ln for ln in out.splitlines() if ln.startswith("{")]
        return (json.loads(last[-1]) if last else None), err
