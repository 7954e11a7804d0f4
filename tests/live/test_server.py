"""The live server's log and its IPv6 binds (fsrlab.live.server, fsrlab.live.hosts; issue 40).

Reference: RFC 6455 §4.1 (a websocket opening handshake and its ``Sec-WebSocket-Protocol``; Bokeh's
client sends ``bokeh, <session token>``), RFC 3986 §3.2.2 (an IPv6 address in a URL is written in
brackets), and docs/live.md's rules: the token never in a log line, a bad websocket request one log line
and no traceback. The requests are made over a real socket to a real ``fsrlab live``.
"""

from __future__ import annotations

import base64
import http.client
import os
import re
import socket

import pytest

from browser import LiveServer
from fsrlab.live.hosts import HostPolicy, origin_netloc, redacted
from fsrlab.live.server import page_url


def test_token_is_redacted_from_a_request_line():
    assert redacted("/ws?token=s3cret") == "/ws?token=…"
    assert redacted("/?a=1&token=s3cret&b=2") == "/?a=1&token=…&b=2"
    assert redacted("/static/x.js") == "/static/x.js"


def test_websocket_needs_bokehs_subprotocol_and_its_pages_origin():
    policy = HostPolicy("127.0.0.1")
    ok = {"Sec-WebSocket-Protocol": "bokeh, abc", "Origin": "http://localhost:5006"}
    assert policy.refusal("localhost:5006", "/ws", None, ok) is None
    assert policy.refusal("localhost:5006", "/ws", None, {})[0] == 400
    assert policy.refusal("localhost:5006", "/ws", None, {**ok, "Sec-WebSocket-Protocol": "chat"})[0] == 400
    assert policy.refusal("localhost:5006", "/ws", None, {**ok, "Origin": "http://localhost:9999"})[0] == 403
    assert origin_netloc("http://[::1]:5006") == "[::1]:5006"


@pytest.mark.parametrize("host, url", [("127.0.0.1", "http://127.0.0.1:5006/"), ("localhost", "http://127.0.0.1:5006/"),
                                       ("::1", "http://[::1]:5006/"), ("::", "http://[::]:5006/?token=t"),
                                       ("0.0.0.0", "http://0.0.0.0:5006/?token=t")])
def test_page_url_brackets_ipv6(host, url):
    assert page_url(host, 5006, "t" if "token" in url else None) == url


def _ws(conn_host: str, port: int, host: str, query: str = "", protocol: str | None = None) -> int:
    headers = {"Host": host, "Origin": f"http://{host}", "Connection": "Upgrade", "Upgrade": "websocket",
               "Sec-WebSocket-Version": "13", "Sec-WebSocket-Key": base64.b64encode(os.urandom(16)).decode()}
    if protocol:
        headers["Sec-WebSocket-Protocol"] = protocol
    c = http.client.HTTPConnection(conn_host, port, timeout=10)
    try:
        c.request("GET", "/ws" + query, headers=headers)
        return c.getresponse().status
    finally:
        c.close()


def test_log_holds_no_token_and_a_bad_websocket_one_line():
    server = LiveServer("--virtual", "--host", "127.0.0.2")
    try:
        port, token = int(re.search(r":(\d+)/", server.url).group(1)), server.info["token"]
        assert _ws("127.0.0.2", port, f"127.0.0.2:{port}", f"?token={token}") == 400  # no Bokeh subprotocol
        # One more request answered: the server's one thread has logged the first (it logs after answering).
        c = http.client.HTTPConnection("127.0.0.2", port, timeout=10)
        c.request("GET", f"/favicon.ico?token={token}", headers={"Host": f"127.0.0.2:{port}"})
        assert c.getresponse().status == 200
        c.close()
    finally:
        _, err = server.stop()
    assert token not in err and "Traceback" not in err, err
    assert re.search(r"^400 GET /ws\?token=… \([0-9.]+\) [0-9.]+ms$", err, re.M), err


def _ipv6() -> bool:
    try:
        with socket.socket(socket.AF_INET6) as s:
            s.bind(("::1", 0))
        return True
    except OSError:
        return False


@pytest.mark.skipif(not _ipv6(), reason="this machine has no IPv6 loopback")
@pytest.mark.parametrize("bind", ["::1", "::"])
def test_ipv6_binds_serve_their_bracketed_url(bind):
    server = LiveServer("--virtual", "--host", bind)
    try:
        m = re.match(r"http://\[([0-9a-f:]+)\]:(\d+)/(\?token=.+)?$", server.url)
        assert m and m.group(1) == bind, server.url
        port, query = int(m.group(2)), m.group(3) or ""
        c = http.client.HTTPConnection("::1", port, timeout=10)
        c.request("GET", "/" + query, headers={"Host": f"[{bind}]:{port}"})
        r = c.getresponse()
        page = r.read()
        c.close()
        assert r.status == 200
        session = re.search(rb'"token":\s*"([^"]+)"', page).group(1).decode()
        assert _ws("::1", port, f"[{bind}]:{port}", query, f"bokeh, {session}") == 101
    finally:
        _, err = server.stop()
    assert "Traceback" not in err and "Invalid host" not in err, err
