"""A page of another site, reaching the live server through a name that resolves to 127.0.0.1 (DNS
rebinding), in a real headless Chromium: it gets no page and cannot open the session's websocket.

Reference: what a browser sends (RFC 7230 §5.4: Host is the name in the URL; RFC 6455 §4.1: a
websocket from a page carries Origin = the page's origin, here equal to Host). Chromium's
``--host-resolver-rules="MAP evil.example 127.0.0.1"`` plays the attacker's DNS. The control: the
same script from the page's own origin opens the websocket.
"""

from __future__ import annotations

import re
import urllib.request

import pytest

from browser import CHROMEDRIVER, CHROMIUM, LiveServer
from toolcheck import require_file

# Open a websocket to the page's own origin with Bokeh's subprotocols; report whether it opened.
WS_JS = """
const done = arguments[arguments.length - 1];
let ws;
try { ws = new WebSocket(`ws://${location.host}/ws`, ["bokeh", arguments[0]]); }
catch (e) { done("threw: " + e); return; }
ws.onopen = () => { ws.close(); done("open"); };
ws.onerror = () => done("error");
ws.onclose = (ev) => done("closed " + ev.code);
"""


@pytest.fixture
def evil_driver():
    require_file(CHROMIUM, "Debian's chromium")
    require_file(CHROMEDRIVER, "Debian's chromium-driver")
    from selenium import webdriver
    from selenium.webdriver.chrome.service import Service

    opts = webdriver.ChromeOptions()
    opts.binary_location = CHROMIUM
    for arg in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                "--host-resolver-rules=MAP evil.example 127.0.0.1", "--no-proxy-server"):
        opts.add_argument(arg)
    d = webdriver.Chrome(service=Service(CHROMEDRIVER), options=opts)
    d.set_script_timeout(20)
    yield d
    d.quit()


def test_a_page_under_another_host_name_cannot_open_the_session(evil_driver):
    server = LiveServer("--virtual")
    try:
        port = int(re.match(r"http://127\.0\.0\.1:(\d+)/", server.url).group(1))
        with urllib.request.urlopen(server.url, timeout=10) as r:  # a valid session token, from the real page
            token = re.search(rb'"token":\s*"([^"]+)"', r.read()).group(1).decode()
        d = evil_driver
        d.get(f"http://evil.example:{port}/")
        body = d.find_element("tag name", "body").text
        assert body.startswith("403") and "answers only to" in body, body
        assert d.execute_script("return typeof Bokeh") == "undefined"  # no page, no BokehJS
        fetched = d.execute_async_script(
            "const done = arguments[0]; "
            "fetch('/static/js/bokeh.min.js').then(r => done(r.status), e => done(String(e)));")
        assert fetched == 403
        assert d.execute_async_script(WS_JS, token) != "open"  # even holding a real session token
        # The control: the page's own origin opens the same websocket.
        d.get(server.url)
        assert d.execute_async_script(WS_JS, token) == "open"
    finally:
        _, err = server.stop()
    assert "Traceback" not in err, err
