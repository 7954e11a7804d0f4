"""Who the live server answers (fsrlab.live.hosts): Host names, the token, the paths served.

Reference: RFC 7230 §5.4 (the Host header carries the name the client used, with an optional port;
an IPv6 address in brackets), RFC 6455 §4.1–4.2 (a websocket opening handshake: GET with Upgrade,
answered 101 when accepted), and the rules docs/live.md states. A DNS-rebinding page reaches
127.0.0.1 with its own name in Host and an Origin equal to it; the requests below are made exactly
so, over a real socket to a real `fsrlab live`.
"""

from __future__ import annotations

import base64
import http.client
import os
import re

import pytest

from browser import LiveServer
from clirun import run_cli
from fsrlab.live.hosts import HostPolicy, check_bind_host, host_name

# ---- the rules -----------------------------------------------------------------------------------

@pytest.mark.parametrize("header, name", [
    ("localhost:5006", "localhost"), ("LOCALHOST", "localhost"), ("127.0.0.1:80", "127.0.0.1"),
    ("[::1]:5006", "::1"), ("[::1]", "::1"), ("evil.example.:5006", "evil.example"),
    ("", None), (None, None), ("a b", None), ("x:y:z", None), ("[::1", None), ("host:99999999", None),
])
def test_host_name_of_a_header(header, name):
    assert host_name(header) == name


def test_loopback_bind_answers_only_loopback_names():
    p = HostPolicy("127.0.0.1")
    for ok in ("127.0.0.1:5006", "localhost:8080", "[::1]:5006", "localhost"):
        assert p.host_ok(ok), ok
    for bad in ("evil.example:5006", "127.0.0.1.evil.example", "10.0.0.5:5006", "", None, "localhost.evil"):
        assert not p.host_ok(bad), bad
    assert p.token_ok(None)  # no token on the loopback


def test_other_binds_answer_their_name_and_need_the_token():
    p = HostPolicy("192.168.1.20", token="s3cret")
    assert p.host_ok("192.168.1.20:5006") and p.host_ok("localhost:5006")
    assert not p.host_ok("10.0.0.1:5006") and not p.host_ok("evil.example:5006")
    assert p.token_ok("s3cret") and not p.token_ok("s3cre") and not p.token_ok(None)
    wild = HostPolicy("0.0.0.0", token="s3cret")
    assert wild.host_ok("10.0.0.1:5006") and wild.host_ok("[fe80::1]:5006")
    assert not wild.host_ok("evil.example:5006")  # rebinding needs a name; an address is safe
    assert wild.refusal("10.0.0.1", "/static/js/bokeh.min.js", None)[0] == 403
    assert wild.refusal("10.0.0.1", "/metadata", "s3cret")[0] == 404
    assert wild.refusal("10.0.0.1", "/", "s3cret") is None


@pytest.mark.parametrize("text", ["", "  ", "a b", "-", "x" * 300, "http://x"])
def test_bind_host_checked(text):
    with pytest.raises(ValueError, match="^host: "):
        check_bind_host(text)


def test_live_empty_host_is_one_line_naming_the_option(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(["live", "--virtual", "--host", "", "--duration", "1s"])
    assert code == 2 and err.count("\n") == 1 and "--host" in err and "is empty" in err, err


# ---- a real server -------------------------------------------------------------------------------

def _port(url: str) -> int:
    return int(re.match(r"http://[^/]+:(\d+)/", url).group(1))


def _get(port: int, path: str, host: str, headers: dict | None = None) -> tuple[int, bytes]:
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        c.request("GET", path, headers={"Host": host, **(headers or {})})
        r = c.getresponse()
        return r.status, r.read()
    finally:
        c.close()


def _upgrade(port: int, host: str, session_token: str | None, query: str = "", cookie: str | None = None) -> int:
    """Status of a websocket opening handshake (RFC 6455 §4.1) with Origin equal to Host, as a rebinding page sends."""
    headers = {"Host": host, "Origin": f"http://{host}", "Connection": "Upgrade", "Upgrade": "websocket",
               "Sec-WebSocket-Version": "13", "Sec-WebSocket-Key": base64.b64encode(os.urandom(16)).decode()}
    if session_token:
        headers["Sec-WebSocket-Protocol"] = f"bokeh, {session_token}"
    if cookie:
        headers["Cookie"] = cookie
    c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
    try:
        c.request("GET", "/ws" + query, headers=headers)
        return c.getresponse().status
    finally:
        c.close()


def _session_token(page: bytes) -> str:
    return re.search(rb'"token":\s*"([^"]+)"', page).group(1).decode()


def test_loopback_server_refuses_other_names_on_every_route_and_the_websocket():
    server = LiveServer("--virtual")
    try:
        port = _port(server.url)
        status, page = _get(port, "/", f"127.0.0.1:{port}")
        assert status == 200
        token = _session_token(page)
        # This computer's names: served, and the websocket opens (101).
        assert _get(port, "/", f"localhost:{port}")[0] == 200
        assert _upgrade(port, f"127.0.0.1:{port}", token) == 101
        # The page and every route under another name: refused, the page's session token never given out.
        for path in ("/", "/static/js/bokeh.min.js", "/favicon.ico", "/ws"):
            status, body = _get(port, path, f"evil.example:{port}")
            assert status == 403 and b"token" not in body.lower().replace(b"needs the token", b""), (path, status)
        assert _upgrade(port, f"evil.example:{port}", token) == 403
        # Only the page's paths are served.
        for path in ("/metadata", "/autoload.js", "/denied", "/etc/passwd"):
            assert _get(port, path, f"127.0.0.1:{port}")[0] == 404, path
    finally:
        _, err = server.stop()
    assert "Traceback" not in err


def test_other_interface_needs_the_token_on_every_route_and_a_bad_one_prints_no_traceback():
    server = LiveServer("--virtual", "--host", "127.0.0.2")
    try:
        port, token = _port(server.url), server.info["token"]
        host = f"127.0.0.2:{port}"
        c = http.client.HTTPConnection("127.0.0.2", port, timeout=10)

        def get(path, headers=None):
            c.request("GET", path, headers={"Host": host, **(headers or {})})
            r = c.getresponse()
            return r.status, r.read()

        for path in ("/", "/static/js/bokeh.min.js", "/favicon.ico", "/ws", "/metadata"):
            assert get(path)[0] == 403, path
            assert get(path + "?token=wrong")[0] == 403, path
        assert get(f"/static/js/bokeh.min.js?token={token}")[0] == 200
        assert get("/favicon.ico", {"Cookie": f"fsrlab_token={token}"})[0] == 200
        c.close()
        for query in ("", "?token=wrong", "?token="):
            c = http.client.HTTPConnection("127.0.0.2", port, timeout=10)
            c.request("GET", "/ws" + query, headers={"Host": host, "Origin": f"http://{host}", "Connection": "Upgrade",
                                                     "Upgrade": "websocket", "Sec-WebSocket-Version": "13",
                                                     "Sec-WebSocket-Key": base64.b64encode(os.urandom(16)).decode(),
                                                     "Sec-WebSocket-Protocol": "bokeh, not-a-session-token"})
            assert c.getresponse().status == 403
            c.close()
    finally:
        _, err = server.stop()
    assert "Traceback" not in err, err
