"""The live page's web server: Bokeh's server (Tornado), bound to one interface, with a token when not local.

Security rules (docs/live.md): the server binds to 127.0.0.1 unless told otherwise; on any other
interface every request needs the random token printed with the URL (``?token=...``, then a cookie
for the page's own requests) and gets 403 without it; the websocket that carries the page's commands
accepts only the page's own origin (Bokeh's ``allow_websocket_origin``); every request, the websocket
included, is first checked for its Host name, token and path (:mod:`fsrlab.live.hosts`): only the page,
BokehJS's static files, the favicon and the websocket are served. BokehJS comes from the ``bokeh`` wheel: nothing is
loaded
from a CDN, the page works offline.
"""

from __future__ import annotations

import secrets
from dataclasses import dataclass

__all__ = ["LiveServer", "start_server", "page_url"]

COOKIE = "fsrlab_token"


def _token_auth(token: str):
    """A Bokeh auth provider: the token as a query argument (sets a cookie) or the cookie itself."""
    from bokeh.server.auth_provider import AuthProvider
    from tornado.web import RequestHandler

    class Denied(RequestHandler):
        def get(self) -> None:
            self.set_status(403)
            self.finish("403: this fsrlab live page needs the token printed with its URL\n")

    class TokenAuth(AuthProvider):
        @property
        def get_user(self):
            def user(handler):
                given = handler.get_argument("token", None) or handler.get_cookie(COOKIE)
                if given is None or not secrets.compare_digest(str(given), token):
                    return None
                if handler.get_argument("token", None) and hasattr(handler, "set_cookie") \
                        and not hasattr(handler, "ws_connection"):
                    handler.set_cookie(COOKIE, token, httponly=True, samesite="Strict")
                return "fsrlab"
            return user

        @property
        def login_url(self):
            return "/denied"

        @property
        def login_handler(self):
            return Denied

    return TokenAuth()


@dataclass
class LiveServer:
    """A running live server.

    Attributes
    ----------
    server : bokeh.server.server.Server
        Bokeh's server (call ``server.io_loop.start()`` to serve, ``server.stop()`` to end).
    url : str
        The page's address, with the token when one is needed.
    token : str or None
        The access token (None on 127.0.0.1).
    """

    server: object
    url: str
    token: str | None


def start_server(make_doc, host: str = "127.0.0.1", port: int = 5006, token: str | None = None) -> LiveServer:
    """Create and start the server (not its loop) for the document maker ``make_doc(doc)``.

    Parameters
    ----------
    make_doc : callable
        Fills one tab's Bokeh document.
    host : str
        Interface to bind: ``127.0.0.1`` (default, this computer only) or another address (then a token
        is required).
    port : int
        TCP port; 0 picks a free one. [1]
    token : str, optional
        Access token for a non-local host; a random one (128 bits) by default.

    Returns
    -------
    LiveServer
    """
    from bokeh.application import Application
    from bokeh.application.handlers.function import FunctionHandler
    from bokeh.server.server import Server

    from fsrlab.live.hosts import LOOPBACK_NAMES, HostPolicy, check_bind_host, guard

    host = check_bind_host(host)
    local = host in LOOPBACK_NAMES
    if not local and token is None:
        token = secrets.token_urlsafe(16)
    if port == 0:  # the origin allowlist must name the port: take a free one now
        port = _free_port(host)
    # Bokeh's origin allowlist takes names and IPv4 addresses only: it lists one origin, and the guard, having
    # checked that a websocket's Origin is the page it names in Host, hands Bokeh that one (fsrlab.live.hosts).
    origin = f"127.0.0.1:{port}"
    options = {"address": host, "port": port, "allow_websocket_origin": [origin],
               "check_unused_sessions_milliseconds": 2000, "unused_session_lifetime_milliseconds": 5000}
    if not local:
        options["auth_provider"] = _token_auth(token)
    server = Server({"/": Application(FunctionHandler(make_doc))}, **options)
    guard(server._tornado, HostPolicy(host, None if local else token), origin=f"http://{origin}")
    server.start()
    return LiveServer(server, page_url(host, port, None if local else token), token if not local else None)


def page_url(host: str, port: int, token: str | None = None) -> str:
    """The live page's address for a server bound to ``host``: the loopback as ``127.0.0.1`` (or ``[::1]`` when
    bound there), an IPv6 address in brackets (RFC 3986 §3.2.2), the token in the query.

    Parameters
    ----------
    host : str
        The interface bound (:func:`fsrlab.live.hosts.check_bind_host`).
    port : int
        The TCP port. [1]
    token : str, optional

    Returns
    -------
    str
    """
    shown = "127.0.0.1" if host in ("127.0.0.1", "localhost") else host
    if ":" in shown:
        shown = f"[{shown}]"
    return f"http://{shown}:{port}/" + (f"?token={token}" if token else "")


def _free_port(host: str) -> int:
    import socket

    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    with socket.socket(family) as probe:
        probe.bind((host, 0))
        return probe.getsockname()[1]
