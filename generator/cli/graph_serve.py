"""``easylab graph --serve MODEL [--listen ADDR:PORT]``: the model's drawing
(the SVG of ``easylab graph``) in a browser page, redrawn when the model's
file or a file it imports is saved; a click on an element shows where it
is declared (``file:line``).

The server polls the files' modification times and tells the page of a new
drawing over server-sent events (``/events``); the page then fetches
``/drawing``: the SVG, the elements' locations by their ids
(graph.element_locations) and the model's errors, if any (the last good
drawing stays on the page under them). Loopback by default; on a loopback
address requests must name a loopback host (no DNS rebinding).
"""

from __future__ import annotations

import asyncio
import json
import signal
import sys
from dataclasses import dataclass, field
from pathlib import Path

from aiohttp import web

from .common import CliError

DEFAULT_LISTEN = "127.0.0.1:8470"
POLL_SECONDS = 0.25
LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1", "[::1]")


@dataclass
class Drawing:
    """The page's data: what /drawing answers; ``version`` grows by one per redraw."""

    version: int = 0
    svg: str | None = None
    locations: dict[str, str] = field(default_factory=dict)
    error: str | None = None

    def as_json(self) -> dict:
        return {"version": self.version, "svg": self.svg, "locations": self.locations, "error": self.error}


def draw(model: Path) -> tuple[str | None, dict[str, str], str | None, list[Path]]:
    """Check and draw ``model``: (SVG or None, locations by element id,
    the errors' report or None, the files the model is made of)."""
    from ..frontend.graph import element_locations, render_dot, run_dot
    from ..pipeline import check_file, model_files

    files = [model]
    try:
        result = check_file(model)
        files = model_files(model, None)
    except (OSError, ValueError) as err:
        return None, {}, f"{model}: {getattr(err, 'strerror', None) or err}", files
    if result.model is None:
        return None, {}, result.report(), files
    try:
        svg = run_dot(render_dot(result.model), "svg").decode("utf-8")
    except RuntimeError as err:
        return None, {}, str(err), files
    svg = svg[svg.index("<svg"):]  # inline in HTML: no XML prolog or doctype
    locations = {eid: f"{span.file}:{span.line}" for eid, span in element_locations(result.model).items()}
    return svg, locations, None, files


def stamps(files: list[Path]) -> tuple:
    """What tells a saved file: each file's modification time and size (None when missing)."""
    out = []
    for f in files:
        try:
            st = f.stat()
            out.append((str(f), st.st_mtime_ns, st.st_size))
        except OSError:
            out.append((str(f), None, None))
    return tuple(out)


class GraphServer:
    """The drawing of one model, kept up to date, and the page's HTTP routes."""

    def __init__(self, model: Path, loopback: bool):
        self.model = model
        self.loopback = loopback
        self.drawing = Drawing()
        self.files: list[Path] = [model]
        self.stamp: tuple = ()
        self.changed = asyncio.Condition()

    async def redraw(self) -> None:
        """Draw the model again (in a thread: checking and Graphviz take time)."""
        before = stamps(self.files)  # taken first: a save while drawing redraws again
        svg, locations, error, files = await asyncio.get_running_loop().run_in_executor(None, draw, self.model)
        self.stamp = before if files == self.files else stamps(files)  # the imports changed
        self.files = files
        d = self.drawing
        if svg is not None:
            d.svg, d.locations = svg, locations
        d.error = error
        d.version += 1
        async with self.changed:
            self.changed.notify_all()

    async def watch(self) -> None:
        """Redraw whenever one of the model's files changes."""
        while True:
            await asyncio.sleep(POLL_SECONDS)
            if stamps(self.files) != self.stamp:
                await self.redraw()

    @web.middleware
    async def loopback_host(self, request: web.Request, handler):
        if self.loopback and request.host.rsplit(":", 1)[0] not in LOOPBACK_HOSTS:
            raise web.HTTPForbidden(text="this drawing is served to loopback host names only")
        return await handler(request)

    def app(self) -> web.Application:
        app = web.Application(middlewares=[self.loopback_host])
        app.router.add_get("/", self.page)
        app.router.add_get("/drawing", self.drawing_json)
        app.router.add_get("/events", self.events)
        return app

    async def page(self, request: web.Request) -> web.Response:
        title = json.dumps(str(self.model))
        return web.Response(text=PAGE.replace("__TITLE__", title[1:-1].replace("<", "&lt;")),
                            content_type="text/html", headers={"Cache-Control": "no-store"})

    async def drawing_json(self, request: web.Request) -> web.Response:
        return web.json_response(self.drawing.as_json(), headers={"Cache-Control": "no-store"})

    async def events(self, request: web.Request) -> web.StreamResponse:
        """Server-sent events: the drawing's version now and after each redraw."""
        response = web.StreamResponse(headers={"Content-Type": "text/event-stream", "Cache-Control": "no-store"})
        await response.prepare(request)
        sent = None
        while True:
            sent = self.drawing.version
            await response.write(f"data: {sent}\n\n".encode())
            async with self.changed:
                try:
                    await asyncio.wait_for(self.changed.wait_for(lambda: self.drawing.version != sent), timeout=15)
                except asyncio.TimeoutError:
                    pass  # the same version again keeps the connection alive


def parse_listen(listen: str) -> tuple[str, int]:
    """``ADDR:PORT`` (``[v6]:PORT`` too) as (host, port); CliError when malformed."""
    host, sep, port = listen.rpartition(":")
    if not sep or not port.isdigit() or not host or int(port) > 65535:
        raise CliError(f"--listen {listen}: expected ADDR:PORT, e.g. {DEFAULT_LISTEN}")
    return host.strip("[]"), int(port)


def serve(model: str, listen: str = DEFAULT_LISTEN) -> int:
    """Serve the drawing of ``model`` until SIGINT or SIGTERM; the page's
    address goes to standard output first."""
    path = Path(model)
    if not path.is_file():
        raise CliError(f"{model}: no such file")
    host, port = parse_listen(listen)
    return asyncio.run(_serve(path, host, port))


async def _serve(path: Path, host: str, port: int) -> int:
    server = GraphServer(path, loopback=host in LOOPBACK_HOSTS)
    await server.redraw()
    runner = web.AppRunner(server.app(), handle_signals=False, shutdown_timeout=1)
    await runner.setup()
    site = web.TCPSite(runner, host, port)
    try:
        await site.start()
    except OSError as err:
        await runner.cleanup()
        raise CliError(f"--listen {host}:{port}: {err.strerror or err}") from None
    bound = runner.addresses[0][1]
    shown = f"[{host}]" if ":" in host else host
    print(f"easylab graph: the drawing of {path} on http://{shown}:{bound}/ (Ctrl-C stops)", flush=True)
    if server.drawing.error:
        print(server.drawing.error, file=sys.stderr, flush=True)
    stop = asyncio.Event()
    loop = asyncio.get_running_loop()
    for sig in (signal.SIGINT, signal.SIGTERM):
        loop.add_signal_handler(sig, stop.set)
    watcher = asyncio.create_task(server.watch())
    await stop.wait()
    watcher.cancel()
    await runner.cleanup()
    return 0


PAGE = """<!doctype html>
<html lang="en"><head><meta charset="utf-8">
<title>__TITLE__ - EasyLab drawing</title>
<link rel="icon" href="data:,">
<style>
 body { font-family: Helvetica, Arial, sans-serif; margin: 0; }
 header { position: sticky; top: 0; background: #f4f4f4; border-bottom: 1px solid #ccc; padding: 6px 10px; }
 #where { font-family: monospace; margin-left: 1em; }
 #error { color: #a00; white-space: pre-wrap; margin: 6px 10px; }
 #diagram { padding: 10px; }
 #diagram g[id].selected > * { stroke: #0060df; stroke-width: 2.5px; }
 #diagram g[id] { cursor: pointer; }
</style></head>
<body>
<header><b>__TITLE__</b> <span id="version"></span><span id="where">click an element: where it is declared</span></header>
<pre id="error" hidden></pre>
<div id="diagram"></div>
<script>
"use strict";
const state = { version: -1, locations: {}, selected: null };
window.easylabGraph = state;
const diagram = document.getElementById("diagram");
const where = document.getElementById("where");
const errorBox = document.getElementById("error");

async function refresh() {
  const reply = await fetch("drawing", { cache: "no-store" });
  const d = await reply.json();
  if (d.version <= state.version) return;
  if (d.svg !== null) diagram.innerHTML = d.svg;
  state.locations = d.locations;
  errorBox.hidden = !d.error;
  errorBox.textContent = d.error || "";
  state.version = d.version;
  document.getElementById("version").textContent = "drawing " + d.version;
  if (state.selected) select(state.selected);
}

// The element under a click: the innermost <g> whose id has a location.
function elementOf(node) {
  let g = node.closest ? node.closest("g[id]") : null;
  while (g && !(g.id in state.locations)) g = g.parentElement ? g.parentElement.closest("g[id]") : null;
  return g;
}

function select(id) {
  diagram.querySelectorAll("g.selected").forEach((g) => g.classList.remove("selected"));
  const g = document.getElementById(id);
  state.selected = g && id in state.locations ? id : null;
  if (!state.selected) return;
  g.classList.add("selected");
  where.textContent = id + "  " + state.locations[id];
}

diagram.addEventListener("click", (event) => {
  const g = elementOf(event.target);
  if (g) select(g.id);
});

const events = new EventSource("events");
events.onmessage = (event) => { if (Number(event.data) !== state.version) refresh(); };
refresh();
</script>
</body></html>
"""
