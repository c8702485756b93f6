"""Who may use a page served by the host tools: the one request guard of
the service panel (``easylab-service web``) and the online mode
(``easylab-debug web``).

On a loopback address the Host header must name a loopback host (no DNS
rebinding); anywhere else, or with a token, every request needs the token
(a cookie set by ``/?token=...``, or ``Authorization: Bearer ...``); every
request that changes something must be same-origin JSON carrying the
page's CSRF token. Every answer carries the headers that keep the page out
of frames and other sites' scripts.
"""

from __future__ import annotations

import asyncio
import errno
import hmac
import ipaddress
import re
import secrets
import signal
import sys
from dataclasses import dataclass

from aiohttp import web

CSRF_HEADER = "X-EasyLab-CSRF"
TOKEN_RE = re.compile(r"[A-Za-z0-9._~-]{8,128}")
CSP = ("default-src 'self'; script-src 'self'; style-src 'self'; img-src 'self' data: blob:; connect-src 'self'; "
       "frame-ancestors 'none'; base-uri 'none'; form-action 'none'")


class ListenError(ValueError):
    """A --listen or --token the server cannot use (one line for the user)."""


def parse_listen(text: str) -> tuple[str, int]:
    """ADDR:PORT (``[::1]:8080`` for IPv6; port 0 picks a free one)."""
    m = re.fullmatch(r"\[([0-9A-Fa-f:.]+)\]:(\d+)|([^:\[\]]+):(\d+)", text.strip())
    if not m:
        raise ListenError(f"--listen {text}: give ADDR:PORT, e.g. 127.0.0.1:8080 or 0.0.0.0:8080")
    host, port = (m.group(1), m.group(2)) if m.group(1) else (m.group(3), m.group(4))
    if host != "localhost":
        try:
            ipaddress.ip_address(host)
        except ValueError:
            raise ListenError(f"--listen {text}: {host} is not an IP address (or localhost)") from None
    if not 0 <= int(port) <= 65535:
        raise ListenError(f"--listen {text}: port {port} is not 0..65535")
    return host, int(port)


def is_loopback(host: str) -> bool:
    """True for localhost and the loopback addresses (127.0.0.0/8, ::1)."""
    host = host.strip("[]").lower()
    if host in ("localhost", "localhost."):
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def host_name(host_header: str) -> str:
    """The name in a Host header, without its port ("[::1]:80" -> "::1")."""
    m = re.fullmatch(r"\[([^\]]*)\](?::\d*)?|([^:]*)(?::\d*)?", host_header)
    return (m.group(1) or m.group(2) or "") if m else host_header


@dataclass
class Guard:
    """Who may use the page: `token` None means no token (loopback only),
    `loopback` means the Host header must be a loopback name; `cookie` the
    name of the cookie holding the token."""

    token: str | None
    loopback: bool
    csrf: str
    cookie: str

    def authorized(self, request: web.Request) -> bool:
        if self.token is None:
            return True
        offered = request.cookies.get(self.cookie)
        auth = request.headers.get("Authorization", "")
        if auth.startswith("Bearer "):
            offered = auth[7:].strip()
        return offered is not None and hmac.compare_digest(offered.encode(), self.token.encode())

    def cross_site(self, request: web.Request) -> str | None:
        """Why a request that changes something is refused (None: it is the
        page's own): it must come from the page's origin, as JSON, with the
        CSRF token that only the page can read."""
        origin = request.headers.get("Origin")
        if origin is not None and origin != f"{request.scheme}://{request.host}":
            return f"a request from another origin ({origin})"
        site = request.headers.get("Sec-Fetch-Site")
        if origin is None and site not in (None, "same-origin", "none"):
            return f"a {site} request"
        if request.content_type != "application/json":
            return "a request that is not JSON"
        if not hmac.compare_digest(request.headers.get(CSRF_HEADER, "").encode(), self.csrf.encode()):
            return f"a request without the panel's {CSRF_HEADER} header"
        return None


def make_guard(host: str, token: str | None, cookie: str) -> Guard:
    """The guard for a listener on `host`: a token is required off loopback
    (made here when none is given) and whenever one is given."""
    if token is not None and not TOKEN_RE.fullmatch(token):
        raise ListenError("--token: give 8 to 128 characters among letters, digits and . _ ~ -")
    loopback = is_loopback(host)
    if token is None and not loopback:
        token = secrets.token_urlsafe(18)
    return Guard(token, loopback, secrets.token_urlsafe(18), cookie)


def refusal(request: web.Request, status: int, message: str) -> web.Response:
    """A refusal: JSON for the API, a line of text for a person's browser."""
    if request.path.startswith("/api/"):
        return web.json_response({"error": message}, status=status)
    return web.Response(status=status, text=message + "\n", content_type="text/plain")


def guard_middleware(guard: Guard, page: str, prog: str):
    """The aiohttp middleware that applies `guard` to every request of a
    `page` ("panel", "page") served by the command `prog` (named in the
    refusals), and adds the security headers to every answer."""

    async def checked(request: web.Request, handler) -> web.StreamResponse:
        if guard.loopback and not is_loopback(host_name(request.host)):
            return refusal(request, 403, f"this {page} answers only to a loopback address, not to '{request.host}'")
        if guard.token is not None and request.path == "/" and "token" in request.query:
            if not hmac.compare_digest(request.query["token"].encode(), guard.token.encode()):
                return refusal(request, 401, f"wrong token: open the address that {prog} printed")
            # The token becomes a cookie and leaves the address bar (and the history).
            response = web.Response(status=303, headers={"Location": "/"})
            response.set_cookie(guard.cookie, guard.token, httponly=True, samesite="Strict", path="/")
            return response
        if not guard.authorized(request):
            return refusal(request, 401, f"this {page} needs its token: open the address that {prog} printed "
                                         "(http://HOST:PORT/?token=...), or send 'Authorization: Bearer TOKEN'")
        if request.method not in ("GET", "HEAD"):
            why = guard.cross_site(request)
            if why is not None:
                print(f"{prog}: refused {why} to {request.path}", file=sys.stderr, flush=True)
                return refusal(request, 403, f"refused: {why}")
        try:
            return await handler(request)
        except web.HTTPException as exc:  # 404, 405 ...: as plain responses, headers added below
            return web.Response(status=exc.status, text=exc.text, content_type="text/plain")

    @web.middleware
    async def middleware(request: web.Request, handler) -> web.StreamResponse:
        response = await checked(request, handler)
        response.headers["Content-Security-Policy"] = CSP
        response.headers["X-Content-Type-Options"] = "nosniff"
        response.headers["X-Frame-Options"] = "DENY"
        response.headers["Referrer-Policy"] = "no-referrer"
        response.headers.setdefault("Cache-Control", "no-store" if request.path.startswith("/api/") else "no-cache")
        return response

    return middleware


async def serve(app: web.Application, host: str, port: int, guard: Guard, cookie: str, title: str,
                start, stop) -> None:
    """Serve ``app`` on host:port until SIGINT or SIGTERM: print the page's
    address (``title``: what it serves) with its token, name the guard's
    cookie ``cookie_PORT`` (cookies ignore ports), call ``start()`` once
    listening and ``stop()`` (in a thread) at the end. ListenError when
    the address cannot be had."""
    runner = web.AppRunner(app, access_log=None, handle_signals=False)
    await runner.setup()
    site = web.TCPSite(runner, host, port, reuse_address=True)
    try:
        await site.start()
    except OSError as err:
        await runner.cleanup()
        why = "the port is in use" if err.errno == errno.EADDRINUSE else (err.strerror or str(err))
        raise ListenError(f"cannot listen on {host}:{port}: {why}") from None
    done = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, done.set)
    bound = runner.addresses[0][1]
    guard.cookie = f"{cookie}_{bound}"
    shown = f"[{host}]" if ":" in host else host
    url = f"http://{shown}:{bound}/" + (f"?token={guard.token}" if guard.token else "")
    print(f"{title}: {url}", flush=True)
    if not guard.loopback:
        print(f"listening on {host}: open it with this machine's address and the token {guard.token}", flush=True)
    start()
    try:
        await done.wait()
    finally:
        await runner.cleanup()
        await asyncio.to_thread(stop)
