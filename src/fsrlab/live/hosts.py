"""Who the live server answers: the Host names it serves, the token, and the paths it serves.

A browser sends the name it used in the ``Host`` header. A page of another site whose name was made
to resolve to this computer (DNS rebinding) reaches the server under *that* name, and a websocket it
opens has ``Origin`` equal to ``Host``, which Tornado counts as the same origin (Bokeh's
``allow_websocket_origin`` is then never consulted). So the server checks the Host header itself,
on every request, the websocket included, before any handler runs:

- the names it answers: ``127.0.0.1``, ``localhost`` and ``::1`` (any port: an SSH tunnel changes
  it), plus the ``--host`` it was given; on a wildcard bind (``0.0.0.0``, ``::``) also any address
  written as numbers and this computer's own name (rebinding needs a name, never an address);
- on an interface other than the loopback, every request needs the token (``?token=`` or the
  cookie the page sets), static files and the websocket too; a missing or wrong one gets 403 and
  no handler runs (nothing is logged but the request line);
- only the page (``/``), its websocket (``/ws``), BokehJS's files (``/static/...``) and
  ``/favicon.ico`` are served; any other path (Bokeh's ``/metadata``, ``/autoload.js``) is 404;
- a websocket request must ask for Bokeh's subprotocol (else 400, one access-log line, no traceback)
  and, when it has an ``Origin``, come from the page it names in ``Host`` (else 403);
- the access log never holds the token (``/ws?token=…``).
"""

from __future__ import annotations

import ipaddress
import re
import secrets
import socket

from fsrlab.errors import ParameterError

__all__ = ["LOOPBACK_NAMES", "WILDCARD_BINDS", "COOKIE", "check_bind_host", "host_name", "origin_netloc", "redacted",
           "log_request", "HostPolicy", "guard"]

LOOPBACK_NAMES = ("127.0.0.1", "localhost", "::1")
WILDCARD_BINDS = ("0.0.0.0", "::")
COOKIE = "fsrlab_token"
_PATHS = re.compile(r"^/(?:|ws|favicon\.ico|static/.*)$")
_NAME = re.compile(r"^[a-z0-9._-]+$")
_LABEL = r"(?!-)[a-z0-9_-]{1,63}(?<!-)"
_BIND_NAME = re.compile(rf"^{_LABEL}(?:\.{_LABEL})*$")


def check_bind_host(host: str) -> str:
    """The interface to bind, checked: an address or a host name, not empty.

    Parameters
    ----------
    host : str
        As given to ``--host``.

    Returns
    -------
    str
        The host, stripped and in lower case.

    Raises
    ------
    ValueError
        ``"host: ..."`` naming what is allowed.
    """
    text = str(host).strip().lower()
    if text.startswith("[") and text.endswith("]"):
        text = text[1:-1]
    if not text:
        raise ParameterError("is empty; give an interface address such as 127.0.0.1 (default) or "
                "0.0.0.0", parameter="host")
    try:
        ipaddress.ip_address(text)
        return text
    except ValueError:
        pass
    if not _BIND_NAME.match(text) or len(text) > 253:
        raise ParameterError(f"{host!r} is neither an IP address nor a host name; give e.g. 127.0.0.1 or "
                "0.0.0.0", parameter="host")
    return text


def host_name(header: str | None) -> str | None:
    """The name in a ``Host`` header, without the port, in lower case (None when malformed).

    Parameters
    ----------
    header : str or None
        ``"localhost:5006"``, ``"[::1]:5006"``, ``"127.0.0.1"``.

    Returns
    -------
    str or None
    """
    if not header:
        return None
    text = header.strip().lower()
    m = re.match(r"^\[([0-9a-f:.]+)\](?::\d{1,5})?$", text)
    if m:
        return m.group(1)
    m = re.match(r"^([^:\[\]]+)(?::\d{1,5})?$", text)
    if not m:
        return None
    name = m.group(1).rstrip(".")
    return name if _NAME.match(name) else None


def _is_address(name: str) -> bool:
    try:
        ipaddress.ip_address(name)
        return True
    except ValueError:
        return False


class HostPolicy:
    """The rules of the module docstring for one server.

    Parameters
    ----------
    bind : str
        The interface the server binds (``--host``).
    token : str or None
        The access token; None on the loopback (no token needed).
    """

    def __init__(self, bind: str, token: str | None = None):
        self.bind = check_bind_host(bind)
        self.token = token
        names = set(LOOPBACK_NAMES) | {self.bind}
        self.wildcard = self.bind in WILDCARD_BINDS
        if self.wildcard:
            names |= {n.lower() for n in (socket.gethostname(), socket.getfqdn()) if n}
        self.names = frozenset(names)

    def host_ok(self, header: str | None) -> bool:
        """Whether a request with this ``Host`` header is for this server."""
        name = host_name(header)
        if name is None:
            return False
        return name in self.names or (self.wildcard and _is_address(name))

    def token_ok(self, given: str | None) -> bool:
        """Whether the token (query or cookie) opens the server; always True without a token."""
        if self.token is None:
            return True
        return given is not None and secrets.compare_digest(str(given).encode(), self.token.encode())

    @staticmethod
    def path_ok(path: str) -> bool:
        """Whether the path is one the live page uses."""
        return bool(_PATHS.match(path or ""))

    def refusal(self, host: str | None, path: str, given: str | None, headers=None) -> tuple[int, str] | None:
        """``(status, text)`` of the refusal for a request, or None when it may pass.

        ``headers`` (the request's): a websocket request is refused with 400 unless it asks for Bokeh's
        subprotocol (``bokeh, <session token>``), and with 403 when its ``Origin`` is not the page it names
        in ``Host``."""
        if not self.host_ok(host):
            return 403, ("403: this fsrlab live page answers only to " + ", ".join(sorted(self.names))
                         + (" or an IP address" if self.wildcard else "") + "\n")
        if not self.token_ok(given):
            return 403, "403: this fsrlab live page needs the token printed with its URL\n"
        if not self.path_ok(path):
            return 404, "404: not found\n"
        if path == "/ws" and headers is not None:
            protocols = [p.strip() for p in (headers.get("Sec-WebSocket-Protocol") or "").split(",")]
            if len(protocols) != 2 or protocols[0] != "bokeh" or not protocols[1]:
                return 400, "400: the live page's websocket speaks Bokeh's protocol (subprotocol bokeh) only\n"
            origin = headers.get("Origin")
            if origin is not None and origin_netloc(origin) != (host or "").strip().lower():
                return 403, "403: this websocket is the live page's own (its Origin must be the page)\n"
        return None


def origin_netloc(origin: str) -> str | None:
    """The ``host[:port]`` of an ``Origin`` header, in lower case (None when it is not a URL).

    Parameters
    ----------
    origin : str
        ``"http://localhost:5006"``, ``"http://[::1]:5006"``.

    Returns
    -------
    str or None
    """
    from urllib.parse import urlsplit

    try:
        netloc = urlsplit(origin.strip()).netloc
    except ValueError:
        return None
    return netloc.lower() or None


_TOKEN_IN_URI = re.compile(r"(?i)([?&]token=)[^&#\s]*")


def redacted(uri: str) -> str:
    """``uri`` with the value of its ``token`` query arguments replaced by ``…`` (for a log line).

    Parameters
    ----------
    uri : str
        A request's path and query, e.g. ``/ws?token=abc``.

    Returns
    -------
    str
    """
    return _TOKEN_IN_URI.sub(r"\1…", uri)


def log_request(handler) -> None:
    """Tornado's access log line (``status METHOD uri (ip) time``), the token left out of the uri.

    Parameters
    ----------
    handler : tornado.web.RequestHandler
        The request's handler, when it has finished (Tornado's ``log_function`` setting).
    """
    from tornado.log import access_log

    status = handler.get_status()
    method = access_log.info if status < 400 else access_log.warning if status < 500 else access_log.error
    request = handler.request
    method("%d %s %s (%s) %.2fms", status, request.method, redacted(request.uri or ""), request.remote_ip,
           1000.0 * request.request_time())


def _request_token(request) -> str | None:
    """The token of a request: its ``token`` query argument, else the cookie."""
    values = request.query_arguments.get("token")
    if values:
        return values[-1].decode("utf-8", "replace")
    cookie = request.cookies.get(COOKIE)
    return cookie.value if cookie is not None else None


def guard(application, policy: HostPolicy, origin: str | None = None) -> None:
    """Put ``policy`` in front of every route of a Tornado application (Bokeh's ``BokehTornado``), and log
    its requests without the token (:func:`log_request`).

    Parameters
    ----------
    application : tornado.web.Application
        The application; its routing is wrapped in place, before the server starts.
    policy : HostPolicy
    origin : str, optional
        The one origin Bokeh's ``allow_websocket_origin`` lists (``http://127.0.0.1:5006``): a websocket
        request whose Origin the policy found to be the page's own is passed on with it.
    """
    from tornado.web import RequestHandler

    class Refused(RequestHandler):
        def initialize(self, status: int, text: str) -> None:  # noqa: D401 - tornado's hook
            self._refusal = (status, text)

        def prepare(self) -> None:
            status, text = self._refusal
            self.set_status(status)
            self.set_header("Content-Type", "text/plain; charset=utf-8")
            self.finish(text)

    route = application.find_handler

    def find_handler(request, **kwargs):
        refusal = policy.refusal(request.headers.get("Host"), request.path, _request_token(request), request.headers)
        if refusal is not None:
            return application.get_handler_delegate(request, Refused, {"status": refusal[0], "text": refusal[1]})
        if request.path == "/ws" and origin is not None and "Origin" in request.headers:
            # The Origin is the page's own (checked above); Bokeh's allow list, which cannot hold an IPv6
            # address, is given the one origin it lists.
            request.headers["Origin"] = origin
        return route(request, **kwargs)

    application.find_handler = find_handler
    application.settings["log_function"] = log_request
