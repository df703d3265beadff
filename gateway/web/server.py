"""LiveServer: the live view page and its JSON API, served by aiohttp from its own thread.

    web = LiveServer(rt, "127.0.0.1", 8080, token=None)   # port 0 picks a free port
    web.start(); print(web.url); ...; web.stop()

GET  /                      the page (schematic, rolling plot, device points, clients, clock)
GET  /api/signals           {"t", "values": {name: value}, "units": {name: unit}}; ?names=a,b
GET  /api/history?names=a,b {"t": [...], "series": {name: [...]}}: recent samples, oldest first
GET  /api/devices           every device: state, watchdog, faults, points (raw and engineering)
GET  /api/clients           controller audit, open connections, watchdog states, recent events
GET  /api/clock             clock mode, simulated time, step lateness
GET  /api/faults            fault kinds and whether injection is enabled
POST /api/faults            {"device", "kind", "point"?, "delta"?, "code"?}: applied at once through
                            gateway.faults (recorded as a device event). Off unless the server has
                            a token; the request must carry `Authorization: Bearer <token>`,
                            otherwise 403 and nothing is injected.

This is the one module that imports aiohttp. The server runs its own asyncio loop in a thread,
like the Modbus server; every plant read goes through the runtime's PlantPort lock (snapshot.py).
"""
from __future__ import annotations

import asyncio
import dataclasses
import hmac
import json
import logging
from pathlib import Path
from typing import Any

from aiohttp import web

from gateway.event_loop import ServerThread
from gateway.faults import KINDS, parse_cli
from gateway.web import snapshot
from plant.errors import ConfigError, SignalError, TransportError

log = logging.getLogger(__name__)
STATIC = Path(__file__).parent / "static"
#: how often the rolling plot's history is sampled [s wall time]
SAMPLE_PERIOD = 0.25


def _json(data: Any, status: int = 200) -> web.Response:
    return web.Response(text=json.dumps(data, allow_nan=False), status=status,
                        content_type="application/json", headers={"Cache-Control": "no-store"})


class LiveServer:
    """HTTP server of one Runtime. `token` None disables POST /api/faults (403)."""

    def __init__(self, rt, host: str = "127.0.0.1", port: int = 8080, *, token: str | None = None):
        self.rt, self.host, self.port = rt, host, port
        self.token = token or None
        self.events = snapshot.EventLog()
        self.history = snapshot.SignalHistory(len(rt.house.catalogue.names))
        for d in rt.devices.values():
            d.subscribe(self.events.add)
        self._server = ServerThread("live-view")
        self._runner: web.AppRunner | None = None
        self._sampler: asyncio.Task | None = None

    @property
    def url(self) -> str:
        return f"http://{self.host}:{self.port}/"

    # --------------------------------------------------------------- lifecycle
    def start(self) -> None:
        self._server.start(self._open, f"live view {self.host}:{self.port}",
                           "check the address and that the port is free")

    def stop(self) -> None:
        if not self._server.running:
            return
        try:
            self._server.call(self._close(), 5)
        except Exception:  # stopping anyway
            log.exception("live view: cleanup")
        self._server.stop()

    async def _close(self) -> None:
        if self._sampler is not None:
            self._sampler.cancel()
            await asyncio.gather(self._sampler, return_exceptions=True)
        await self._runner.cleanup()

    async def _open(self) -> None:
        app = web.Application()
        app.add_routes([
            web.get("/", self._page),
            web.get("/api/signals", self._signals),
            web.get("/api/history", self._history),
            web.get("/api/devices", self._devices),
            web.get("/api/clients", self._clients),
            web.get("/api/clock", self._clock),
            web.get("/api/faults", self._fault_kinds),
            web.post("/api/faults", self._inject),
            web.static("/static", STATIC),
        ])
        self._runner = web.AppRunner(app, access_log=None)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.host, self.port)
        await site.start()
        self.port = self._runner.addresses[0][1]
        self._sampler = asyncio.get_running_loop().create_task(self._sample())

    async def _sample(self) -> None:
        while True:
            try:
                self.history.sample(self.rt)
            except Exception:  # server-loop boundary: log and keep sampling
                log.exception("live view: history sample")
            await asyncio.sleep(SAMPLE_PERIOD)

    # ------------------------------------------------------------------ routes
    async def _page(self, request: web.Request) -> web.Response:
        return web.FileResponse(STATIC / "index.html", headers={"Cache-Control": "no-store"})

    async def _signals(self, request: web.Request) -> web.Response:
        data = snapshot.signals(self.rt)
        names = [n for n in request.query.get("names", "").split(",") if n]
        if names:
            unknown = [n for n in names if n not in data["values"]]
            if unknown:
                return _json({"error": f"/api/signals: unknown signals {unknown}; see /api/signals "
                                       "for the names"}, 404)
            data = {"t": data["t"], "values": {n: data["values"][n] for n in names},
                    "units": {n: data["units"][n] for n in names}}
        return _json(data)

    async def _history(self, request: web.Request) -> web.Response:
        names = [n for n in request.query.get("names", "").split(",") if n]
        try:
            return _json(self.history.series(self.rt, names))
        except SignalError as exc:
            return _json({"error": f"/api/history: {exc}"}, 404)

    async def _devices(self, request: web.Request) -> web.Response:
        return _json(snapshot.devices(self.rt))

    async def _clients(self, request: web.Request) -> web.Response:
        return _json(snapshot.clients(self.rt, self.events))

    async def _clock(self, request: web.Request) -> web.Response:
        return _json(snapshot.clock(self.rt))

    async def _fault_kinds(self, request: web.Request) -> web.Response:
        return _json({"enabled": self.token is not None, "kinds": list(KINDS),
                      "devices": sorted(self.rt.devices)})

    async def _inject(self, request: web.Request) -> web.Response:
        if self.token is None:
            return _json({"error": "POST /api/faults: fault injection is off; start the server "
                                   "with --http-token TOKEN"}, 403)
        given = request.headers.get("Authorization", "")
        if not hmac.compare_digest(given.encode(), f"Bearer {self.token}".encode()):
            return _json({"error": "POST /api/faults: missing or wrong token; send "
                                   "'Authorization: Bearer <token>'"}, 403)
        try:
            body = await request.json()
            if not isinstance(body, dict):
                raise ValueError("body must be a JSON object")
            device, kind = str(body["device"]), str(body["kind"])
            point, delta = str(body.get("point", "")), float(body.get("delta", 0.0))
            code = int(body.get("code", 0))
        except (ValueError, KeyError, TypeError) as exc:
            return _json({"error": f"POST /api/faults: {exc}; send JSON {{\"device\", \"kind\", "
                                   "\"point\"?, \"delta\"?, \"code\"?}"}, 400)
        t = self.rt.port.t
        try:
            fault = parse_cli(f"{device}:{kind}:{point}:{delta!r}@{t!r}", self.rt.devices)
            fault = dataclasses.replace(fault, code=code)
            fault.apply(self.rt.devices, self.rt.transports)
        except (ConfigError, ValueError) as exc:
            return _json({"error": f"POST /api/faults: {exc}"}, 400)
        return _json({"t": t, "applied": dataclasses.asdict(fault)})
