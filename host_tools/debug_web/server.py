"""``easylab-debug web``: the online mode, the running model drawn on its
own diagram in a browser (docs/online.md).

    easylab-debug web --map debug_map.json TARGET [--listen ADDR:PORT] [--token T] [--model FILE]

TARGET as for the console: a serial device, a pty, ``tcp:HOST:PORT``.
The server (aiohttp) serves one page and a small JSON API; all debug
traffic goes through one :class:`TargetLink` thread. Safety is the service
panel's (host_tools/web/server.py, whose guard this module uses): on a
loopback address the Host header must name a loopback host; anywhere
else, or with ``--token``, every request needs the token; every request
that changes something must be same-origin JSON with the page's CSRF token.
"""

from __future__ import annotations

import argparse
import asyncio
import json
import sys
from pathlib import Path

from aiohttp import web

from ..debug_console import PROG, CommandError, Session, format_value, parse_value, why_read_only
from ..debug_map import DebugMap, Item, MapError
from ..debug_protocol import K, OPS, STEP_UNITS, DebugError
from ..transport import TransportError
from ..web.server import STATIC as PANEL_STATIC
from ..web_guard import CSRF_HEADER, Guard, ListenError, guard_middleware, make_guard, parse_listen, serve
from .elements import DrawingError, element_ids, elements, model_file, render_svg
from .guards import GuardValues
from ..link_jobs import Busy, NotConnected
from .target import (TargetLink, breakpoint_job, command_job, condition_job, force_job,
                     release_job, write_job)

STATIC = Path(__file__).resolve().parent / "static"
DEFAULT_LISTEN = "127.0.0.1:8090"
MAX_BODY = 64 * 1024
COMMANDS = ("run", "break", "step", "reset")


def _error(status: int, message: str) -> web.Response:
    return web.json_response({"error": message}, status=status)


class OnlinePage:
    """The web application of one target."""

    def __init__(self, dmap: DebugMap, link: TargetLink, guard: Guard, model: dict, job_wait: float):
        self.map = dmap
        self.link = link
        self.guard = guard
        self.model = model  # what /api/model answers, computed once
        self.job_wait = job_wait
        self._model_json: str | None = None

    def app(self) -> web.Application:
        app = web.Application(middlewares=[guard_middleware(self.guard, "page", f"{PROG} web")],
                              client_max_size=MAX_BODY)
        app.router.add_get("/", self.index)
        app.router.add_get("/api/model", self.api_model)
        app.router.add_get("/api/state", self.api_state)
        app.router.add_post("/api/view", self.api_view)
        app.router.add_post("/api/command", self.api_command)
        app.router.add_post("/api/breakpoint", self.api_breakpoint)
        app.router.add_post("/api/write", self.api_write)
        app.router.add_post("/api/force", self.api_force)
        app.router.add_post("/api/release", self.api_release)
        app.router.add_static("/static/", STATIC, follow_symlinks=False)
        app.router.add_static("/vendor/", PANEL_STATIC / "vendor", follow_symlinks=False)
        return app

    # ------------------------------------------------------------ reads

    async def index(self, request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC / "index.html")

    async def api_model(self, request: web.Request) -> web.Response:
        if self._model_json is None:  # the drawing and the text are large: serialised once
            self._model_json = json.dumps({**self.model, "csrf": self.guard.csrf, "csrf_header": CSRF_HEADER})
        return web.Response(text=self._model_json, content_type="application/json")

    async def api_state(self, request: web.Request) -> web.Response:
        try:
            after = int(request.query.get("after", "-1"))
        except ValueError:
            return _error(400, "after: give a snapshot number")
        snaps = self.link.snapshots_after(after)
        return web.json_response({"link": self.link.link_state(), "snapshots": [s.as_json() for s in snaps]})

    # ------------------------------------------------------------ changes

    async def _body(self, request: web.Request) -> dict:
        try:
            body = await request.json()
        except (json.JSONDecodeError, UnicodeDecodeError):
            raise _Refusal(_error(400, "the request is not JSON")) from None
        if not isinstance(body, dict):
            raise _Refusal(_error(400, "give a JSON object"))
        return body

    async def _on_target(self, job):
        try:
            future = self.link.submit(job)
        except Busy as err:
            raise _Refusal(_error(429, f"busy: {err}; try again")) from None
        except NotConnected as err:
            raise _Refusal(_error(503, f"the target is not connected: {err}")) from None
        try:
            return await asyncio.wait_for(asyncio.wrap_future(future), self.job_wait)
        except asyncio.TimeoutError:
            raise _Refusal(_error(504, f"the target did not answer within {self.job_wait:g} s")) from None
        except DebugError as err:
            raise _Refusal(_error(422, str(err))) from None
        except (TransportError, NotConnected) as err:
            raise _Refusal(_error(503, f"the target is not connected: {err}")) from None

    async def api_view(self, request: web.Request) -> web.Response:
        try:
            body = await self._body(request)
        except _Refusal as refusal:
            return refusal.response
        ids = body.get("items")
        if not isinstance(ids, list) or not all(isinstance(i, int) and not isinstance(i, bool) for i in ids):
            return _error(400, 'give {"items": [ID, ...]}')
        return web.json_response({"items": self.link.set_view(ids)})

    async def api_command(self, request: web.Request) -> web.Response:
        try:
            body = await self._body(request)
            command, unit = body.get("command"), body.get("unit")
            if command not in COMMANDS:
                return _error(400, f"command: one of {', '.join(COMMANDS)}")
            if command == "step" and unit not in STEP_UNITS:
                return _error(400, f"unit: one of {', '.join(STEP_UNITS)}")
            await self._on_target(command_job(command, unit, self.map.program_id))
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"done": command})

    async def api_breakpoint(self, request: web.Request) -> web.Response:
        """{"element": ID} sets a breakpoint at the element's probe point,
        {"when": {"name": NAME, "op": OP, "value": VALUE}} a conditional one;
        {"slot": N} clears one, {"slot": "all"} every one."""
        try:
            body = await self._body(request)
            if "when" in body:
                return await self._condition(body["when"])
            if "element" in body:
                info = self.model["elements"].get(body["element"]) if isinstance(body["element"], str) else None
                if info is None or info["point"] is None:
                    return _error(400, f"no breakpoint can go at {body['element']!r}")
                slot = await self._on_target(breakpoint_job(tuple(info["point"]), None))
                return web.json_response({"slot": slot, "at": self.map.describe(*info["point"])})
            slot = body.get("slot")
            if slot != "all" and not (isinstance(slot, int) and not isinstance(slot, bool) and 0 <= slot < 255):
                return _error(400, 'give {"element": ID} or {"slot": N|"all"}')
            await self._on_target(breakpoint_job(None, None if slot == "all" else slot))
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"cleared": slot})

    def _element(self, body: dict, verb: str) -> tuple[Item, int]:
        """The item ``body["name"]`` names (writable unless `verb` is None,
        a condition's item) and ``body["element"]`` (0 by default)."""
        name, element = body.get("name"), body.get("element", 0)
        if not isinstance(name, str):
            raise _Refusal(_error(400, 'give {"name": NAME, "value": VALUE}'))
        try:
            item = self.map.item(name)
        except MapError as err:
            raise _Refusal(_error(400, str(err))) from None
        if verb is not None and not item.writable:
            raise _Refusal(_error(400, f"{item.name} cannot be {verb}: it is read-only ({why_read_only(item)})"))
        if not isinstance(element, int) or isinstance(element, bool) or not 0 <= element < item.count:
            raise _Refusal(_error(400, f"{item.name} has {item.count} element(s)"))
        return item, element

    @staticmethod
    def _value(item: Item, text, in_range: bool = True):
        """The value of `text` for `item`, as the console takes it (a scaled
        item's in engineering units, a chart's state by a step's name)."""
        if not isinstance(text, (str, int, float)) or isinstance(text, bool):
            raise _Refusal(_error(400, f"{item.name}: give the value as text, e.g. \"12\""))
        try:
            value = Session.step_value(item, str(text)) if item.labels is not None else parse_value(item, str(text))
        except CommandError as err:
            raise _Refusal(_error(400, str(err))) from None
        if in_range and item.range and not item.range[0] <= value <= item.range[1]:
            raise _Refusal(_error(400, f"{item.name}: {text} is outside its range {item.range[0]}..{item.range[1]}"))
        return value

    def _needs_slots(self, feature: str) -> None:
        """Refuse (409) what the connected firmware has no slots for."""
        why = self.link.no_slots().get(feature)
        if why is not None and self.link.link_state()["state"] == "connected":
            raise _Refusal(_error(409, why))

    async def api_write(self, request: web.Request) -> web.Response:
        try:
            body = await self._body(request)
            item, element = self._element(body, "written")
            value = self._value(item, body.get("value"))
            how = await self._on_target(write_job(item, value, element))
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"name": item.name, "value": value, "applied": how == K.APPLIED})

    async def api_force(self, request: web.Request) -> web.Response:
        """{"name": NAME, "value": VALUE}: hold an element at VALUE every
        instant until released (a var, param or device `out` datum)."""
        try:
            body = await self._body(request)
            self._needs_slots("force")
            item, element = self._element(body, "forced")
            value = self._value(item, body.get("value"))
            how = await self._on_target(force_job(item, value, element))
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"name": item.name, "forced": value, "shown": format_value(item, value),
                                  "applied": how == K.APPLIED})

    async def api_release(self, request: web.Request) -> web.Response:
        """{"name": NAME} releases one forced element, {"name": "all"} every one."""
        try:
            body = await self._body(request)
            self._needs_slots("force")
            if body.get("name") == "all":
                await self._on_target(release_job(None))
                return web.json_response({"released": "all"})
            item, element = self._element(body, None)
            try:
                await self._on_target(release_job(item, element))
            except _Refusal as refusal:
                if refusal.response.status == 422 and item.id not in {f["item"] for f in self.link.forced}:
                    return _error(422, f"{item.name} is not forced")
                raise
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"released": item.name})

    async def _condition(self, when) -> web.Response:
        """A conditional breakpoint: {"name": NAME, "op": OP, "value": VALUE}."""
        if not isinstance(when, dict) or when.get("op") not in OPS:
            return _error(400, f'give {{"when": {{"name": NAME, "op": OP, "value": VALUE}}}} (OP: {" ".join(OPS)})')
        self._needs_slots("conditions")
        item, element = self._element(when, None)
        value = self._value(item, when.get("value"), in_range=False)
        slot = await self._on_target(condition_job(item, when["op"], value, element))
        name = f"{item.name}[{element}]" if item.count > 1 else item.name
        return web.json_response({"slot": slot, "at": f"when {name} {when['op']} {format_value(item, value)}"})


class _Refusal(Exception):
    def __init__(self, response: web.Response):
        super().__init__(response.status)
        self.response = response


# ====================================================================== running it


def page_model(dmap: DebugMap, model_path: Path, guards: GuardValues | None = None) -> dict:
    """What the page is built from: the drawing, the model's text, the map's
    items, charts and probe points, each element's part in the map."""
    svg = render_svg(model_path)
    els = elements(dmap, element_ids(svg), guards)
    return {"model": dmap.model, "title": dmap.data.get("title"), "program_id": f"0x{dmap.program_id:08x}",
            "tick_us": dmap.tick_us, "file": _shown_path(model_path), "location_file": _location_file(dmap),
            "source": model_path.read_text(encoding="utf-8"), "svg": svg, "elements": els,
            "items": [{"id": it.id, "name": it.name, "kind": it.kind, "type": it.type, "count": it.count,
                       "writable": it.writable, "unit": it.unit, "range": it.range, "location": it.location,
                       "labels": {str(k): v for k, v in it.labels.items()} if it.labels else None}
                      for it in dmap.items],
            "step_units": list(STEP_UNITS)}


def _shown_path(path: Path) -> str:
    """The model's file as the page names it: relative to the working folder when inside it."""
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return path.name


def _location_file(dmap: DebugMap) -> str | None:
    """The file name the map's locations use (``file`` of ``file:line``)."""
    named = next((it.location for it in dmap.items if it.location != "?"), None)
    return named.rsplit(":", 1)[0] if named else None


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog=f"{PROG} web", description="The online mode: the running model on its own "
                                "diagram in a browser (docs/online.md).")
    p.add_argument("target", metavar="TARGET", help="serial device, pty (link) or tcp:HOST:PORT")
    p.add_argument("--map", metavar="FILE", required=True, help="debug_map.json of the build running on the target")
    p.add_argument("--model", metavar="FILE", help="the model's file (default: the one the map's locations name)")
    p.add_argument("--listen", metavar="ADDR:PORT", default=DEFAULT_LISTEN,
                   help=f"where the page is served (default {DEFAULT_LISTEN}; another address than loopback "
                        "needs a token, made when none is given)")
    p.add_argument("--token", metavar="T", help="the token the page asks for (8 to 128 letters, digits, . _ ~ -)")
    p.add_argument("--every", type=float, default=0.05, metavar="S",
                   help="the shortest refresh period in seconds (default 0.05; a slow link makes it longer)")
    p.add_argument("--timeout", type=float, default=0.5, metavar="S", help="answer timeout in seconds (default 0.5)")
    p.add_argument("--baud", type=int, default=115200, help="baud rate of a serial device (default 115200)")
    return p


def main(argv: list[str]) -> int:
    """``easylab-debug web ...``: serve the page until SIGINT or SIGTERM."""
    args = build_parser().parse_args(argv)
    try:
        dmap = DebugMap.load(args.map)
        host, port = parse_listen(args.listen)
        guard = make_guard(host, args.token, "easylab_online")
        path = model_file(dmap, args.model)
        guards = GuardValues.of_model(path, dmap)
        model = page_model(dmap, path, guards)
    except (MapError, ListenError, DrawingError) as err:
        print(f"{PROG} web: error: {err}", file=sys.stderr)
        return 2
    if guards is None:
        print(f"{PROG} web: {path} is not the program of {dmap.path} (0x{dmap.program_id:08x}): the diagram is "
              f"drawn, the guards' values are not shown", file=sys.stderr, flush=True)
    return asyncio.run(_serve(dmap, model, args, host, port, guard, guards))


async def _serve(dmap: DebugMap, model: dict, args, host: str, port: int, guard: Guard,
                 guards: GuardValues | None) -> int:
    def log(line: str) -> None:
        print(f"{PROG} web: {line}", file=sys.stderr, flush=True)
    link = TargetLink(dmap, args.target, elements=model["elements"], guards=guards, timeout=args.timeout,
                      min_period=args.every,
                      baud=args.baud, log=log)
    page = OnlinePage(dmap, link, guard, model, job_wait=max(10.0, 8 * args.timeout))
    try:
        await serve(page.app(), host, port, guard, "easylab_online", f"online mode of model {dmap.model} (target "
                    f"{args.target})", link.start, link.stop)
    except ListenError as err:
        print(f"{PROG} web: error: {err}", file=sys.stderr)
        return 2
    return 0
