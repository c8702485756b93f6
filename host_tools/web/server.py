"""``easylab-service web``: the service panel, one web page built from the
service map that monitors, plots and tunes a running device
(docs/service.md, "The web panel").

The server (aiohttp) serves the page and a small JSON API; all Modbus
traffic goes through one :class:`DeviceSession`. Safety: on a loopback
address the Host header must name a loopback host (no DNS rebinding);
anywhere else, or with ``--token``, every request needs the token (a
cookie set by ``/?token=...``, or ``Authorization: Bearer ...``); every
request that changes something must be same-origin JSON carrying the
page's CSRF token.
"""

from __future__ import annotations

import asyncio
import json
import re
import sys
import time
from dataclasses import asdict
from pathlib import Path

from aiohttp import web

from ..modbus_link import EXCEPTIONS, DeviceException, LinkError
from ..service_cli import (PROG, UsageError, backup_document, device_address, parse_period, plan_restore,
                           read_values, restore_params, write_value)
from ..service_map import MapError, ServiceItem, ServiceMap, ValueError_
from ..web_guard import CSRF_HEADER, Guard, ListenError, guard_middleware, make_guard, parse_listen, serve
from ..link_jobs import Busy, NotConnected
from .session import DeviceSession, json_value

STATIC = Path(__file__).resolve().parent / "static"
DEFAULT_LISTEN = "127.0.0.1:8080"
MAX_BODY = 256 * 1024  # a restore of a few thousand params fits


def _error(status: int, message: str, **extra) -> web.Response:
    return web.json_response({"error": message, **extra}, status=status)


# ====================================================================== the application


class Panel:
    """The web application of one device session."""

    def __init__(self, smap: ServiceMap, session: DeviceSession, guard: Guard, job_wait: float):
        self.smap = smap
        self.session = session
        self.guard = guard
        self.job_wait = job_wait

    def app(self) -> web.Application:
        app = web.Application(middlewares=[guard_middleware(self.guard, "panel", f"{PROG} web")],
                              client_max_size=MAX_BODY)
        app.router.add_get("/", self.index)
        app.router.add_get("/api/map", self.api_map)
        app.router.add_get("/api/samples", self.api_samples)
        app.router.add_post("/api/write", self.api_write)
        app.router.add_get("/api/backup", self.api_backup)
        app.router.add_post("/api/restore", self.api_restore)
        app.router.add_static("/static/", STATIC, follow_symlinks=False)
        return app

    # ------------------------------------------------------------ pages and reads

    async def index(self, request: web.Request) -> web.StreamResponse:
        return web.FileResponse(STATIC / "index.html")

    async def api_map(self, request: web.Request) -> web.Response:
        s = self.smap
        return web.json_response({"model": s.model, "title": s.title, "program_id": s.program_id,
                                  "where": self.session.address.where, "period": self.session.period,
                                  "csrf": self.guard.csrf, "csrf_header": CSRF_HEADER,
                                  "items": [item_json(it) for it in s.items]})

    async def api_samples(self, request: web.Request) -> web.Response:
        try:
            after = int(request.query.get("after", "-1"))
        except ValueError:
            return _error(400, "after: give a sample number")
        samples = self.session.samples_after(after)
        return web.json_response({"now": round(time.time(), 3), "link": self.session.link_state(),
                                  "samples": [s.as_json() for s in samples]})

    # ------------------------------------------------------------ jobs on the device

    async def _on_device(self, job):
        """Run `job` in the device session; an error response is raised as
        _Refusal, so a handler reads as its success path."""
        try:
            future = self.session.submit(job)
        except Busy as err:
            raise _Refusal(_error(429, f"busy: {err}; try again")) from None
        except NotConnected as err:
            raise _Refusal(_error(503, f"the device is not connected: {err}")) from None
        try:
            return await asyncio.wait_for(asyncio.wrap_future(future), self.job_wait)
        except asyncio.TimeoutError:
            raise _Refusal(_error(504, f"the device did not finish within {self.job_wait:g} s")) from None
        except DeviceException as err:
            raise _Refusal(_error(422, str(err), exception=err.code,
                                  words=EXCEPTIONS.get(err.code, "exception"))) from None
        except (LinkError, NotConnected) as err:
            raise _Refusal(_error(503, f"the device is not connected: {err}")) from None

    async def _json_body(self, request: web.Request):
        try:
            return await request.json()
        except (json.JSONDecodeError, UnicodeDecodeError):
            raise _Refusal(_error(400, "the request is not JSON")) from None

    async def api_write(self, request: web.Request) -> web.Response:
        try:
            body = await self._json_body(request)
            if not isinstance(body, dict) or not isinstance(body.get("name"), str) or "value" not in body:
                return _error(400, 'give {"name": NAME, "value": VALUE}')
            try:
                it = self.smap.item(body["name"])
                if not it.writable:
                    return _error(400, f"'{it.name}' is read-only (service ro)")
                value = it.parse(str(body["value"]))
            except (MapError, ValueError_) as err:
                return _error(400, str(err))

            def write_and_read_back(link):
                # Runs between samples: the samples after this one show the write.
                before = self.session.last_seq()
                write_value(link, it, value)
                return read_values(link, [it])[it.name], before
            now, before = await self._on_device(write_and_read_back)
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"name": it.name, "value": json_value(now), "text": it.format(now),
                                  "seq": before, "t": round(time.time(), 3)})

    async def api_backup(self, request: web.Request) -> web.Response:
        try:
            doc = await self._on_device(lambda link: backup_document(self.smap, read_values(link, self.smap.params())))
        except _Refusal as refusal:
            return refusal.response
        name = re.sub(r"[^A-Za-z0-9_.-]", "_", self.smap.model)
        return web.Response(text=json.dumps(doc, indent=2) + "\n", content_type="application/json",
                            headers={"Content-Disposition": f'attachment; filename="{name}-params.json"'})

    async def api_restore(self, request: web.Request) -> web.Response:
        try:
            doc = await self._json_body(request)
            try:
                todo, skipped = plan_restore(doc, self.smap, "the file")
            except (UsageError, ValueError_) as err:
                return _error(400, str(err))
            refused = await self._on_device(lambda link: restore_params(link, todo))
        except _Refusal as refusal:
            return refusal.response
        return web.json_response({"total": len(todo), "restored": len(todo) - len(refused), "skipped": skipped,
                                  "refused": [{"name": it.name, "error": why} for it, why in refused]})


def item_json(it: ServiceItem) -> dict:
    """A map item for the page: its scale as decimal text ("0.1"), and
    whether it is an alarm (ServiceItem.alarm)."""
    return {**asdict(it), "scale": it.scale.text(), "alarm": it.alarm}


class _Refusal(Exception):
    def __init__(self, response: web.Response):
        super().__init__(response.status)
        self.response = response


# ====================================================================== running it


def run_panel(args, smap: ServiceMap) -> int:
    """Serve the panel until SIGINT or SIGTERM (exit status 0)."""
    address = device_address(args, smap)
    period = parse_period(args.every)
    try:
        host, port = parse_listen(args.listen)
        guard = make_guard(host, args.token, "easylab_panel")
    except ListenError as err:
        raise UsageError(str(err)) from None
    return asyncio.run(_serve(smap, address, period, host, port, guard))


async def _serve(smap: ServiceMap, address, period: float, host: str, port: int, guard: Guard) -> int:

    def log(line: str) -> None:
        print(f"{PROG}: {line}", file=sys.stderr, flush=True)
    session = DeviceSession(smap, address, period, log=log)
    panel = Panel(smap, session, guard, job_wait=max(10.0, 3 * address.timeout))
    try:
        await serve(panel.app(), host, port, guard, "easylab_panel",
                    f"service panel of model {smap.model} (device {address.where})", session.start, session.stop)
    except ListenError as err:
        raise UsageError(str(err)) from None
    return 0
