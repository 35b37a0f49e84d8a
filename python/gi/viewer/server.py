"""The viewer's web server (aiohttp): the page and its files, the WebSocket that carries
frames and the page's messages, and the HTTP routes for scripts.

Routes:

- ``GET /``: the page (``static/index.html``, ``viewer.js``, ``viewer.css``; no network
  needed, nothing from a CDN).
- ``GET /ws``: the WebSocket. Server → page: JSON text (``hello``, ``state``, ``picked``,
  ``error``) and binary frames (a 4-byte big-endian length, the frame's JSON description,
  then the PNG). Page → server: JSON messages (:mod:`gi.viewer.messages`); a frame is sent
  only after the page acknowledged the previous one, and frames rendered meanwhile replace
  each other (dropped, never queued).
- ``GET /frame.png``: the current frame, once it shows every change made before the request.
- ``GET /state``: the camera, lights, settings and choices as JSON.
- ``POST /camera``, ``/light``, ``/object``, ``/material``: the JSON that
  :meth:`gi.Renderer.update` takes for ``camera``, ``lights``, ``objects``, ``materials``
  (``{"position": [0, 1, 3]}``, ``{"0": {"position": [...]}}``, ...); ``POST /settings``:
  ``method``, ``estimator``, ``photons``, ``subsample``, ``exposure``, ``tonemap``, ``aov``,
  ``paused``. Each answers once the change is applied: 200 with the state, or 400 with
  ``{"error", "field"}``.

Requests from another site's pages are refused: a WebSocket or POST whose ``Origin`` is not
this server's, or (on a loopback address) whose ``Host`` is not a loopback name (DNS
rebinding).
"""

from __future__ import annotations

import asyncio
import contextlib
import ipaddress
import json
import struct
import time
from dataclasses import dataclass
from importlib import resources
from pathlib import Path
from typing import Any
from urllib.parse import urlsplit

from aiohttp import WSMsgType, web

import gi
from gi.viewer import messages as m
from gi.viewer.engine import DisplayState, Engine, Frame

#: Seconds ``GET /frame.png`` and the POST routes wait for the renderer.
REQUEST_TIMEOUT = 60.0
#: Seconds after which a frame the page has not acknowledged counts as lost.
ACK_TIMEOUT = 5.0
STATIC = {
    "index.html": "text/html",
    "viewer.js": "text/javascript",
    "viewer.css": "text/css",
}
LOOPBACK_NAMES = ("localhost", "127.0.0.1", "::1")


@dataclass
class _Client:
    id: int
    ws: web.WebSocketResponse
    pending: Frame | None = None
    in_flight: int | None = None
    sent_at: float = 0.0


def url_of(host: str, port: int) -> str:
    shown = f"[{host}]" if ":" in host else host
    return f"http://{shown}:{port}/"


def is_loopback(host: str) -> bool:
    if host == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


class ViewerServer:
    """The server of one viewer: an :class:`Engine` rendering ``scene`` and the routes
    above. :meth:`start` and :meth:`stop` run in the event loop that serves it."""

    def __init__(
        self,
        scene: gi.Scene,
        method: str,
        options: dict[str, Any],
        *,
        host: str = "127.0.0.1",
        port: int = 0,
        display: DisplayState | None = None,
        env_dir: str | Path | None = None,
    ) -> None:
        self.host, self.port = host, port
        self._loop: asyncio.AbstractEventLoop | None = None
        self._clients: dict[int, _Client] = {}
        self._next_client = 1
        self._tasks: set[asyncio.Task[Any]] = set()
        self._runner: web.AppRunner | None = None
        self.engine = Engine(
            scene,
            method,
            options,
            on_frame=self._frame_from_thread,
            on_event=self._event_from_thread,
            display=display,
            env_dir=env_dir,
        )
        self.url = ""

    # Life ---------------------------------------------------------------------------------

    async def start(self) -> str:
        """Binds, starts the render thread and returns the page's URL."""
        self._loop = asyncio.get_running_loop()
        app = web.Application(client_max_size=m.MAX_MESSAGE_BYTES)
        app.router.add_get("/", self._page)
        app.router.add_get("/ws", self._websocket)
        app.router.add_get("/frame.png", self._frame_png)
        app.router.add_get("/state", self._state)
        app.router.add_get("/{name}", self._static)
        for route in ("camera", "light", "object", "material", "settings"):
            app.router.add_post(f"/{route}", self._post)
        self._runner = web.AppRunner(app, access_log=None, shutdown_timeout=0.5)
        await self._runner.setup()
        site = web.TCPSite(self._runner, self.host, self.port)
        await site.start()
        sockets = self._runner.addresses
        if sockets:
            self.port = sockets[0][1]
        self.url = url_of(self.host, self.port)
        self.engine.start()
        return self.url

    async def stop(self) -> None:
        """Cancels the frame under way, closes the pages' sockets and stops serving."""
        # Blocks the loop for at most the cancel of the frame under way (the executors may
        # be shut down already when this runs at interpreter exit).
        self.engine.stop()
        for c in list(self._clients.values()):
            with contextlib.suppress(Exception):
                await asyncio.wait_for(c.ws.close(code=1001, message=b"server stopped"), 0.5)
        if self._runner is not None:
            await self._runner.cleanup()
        for t in list(self._tasks):
            t.cancel()

    # From the render thread ---------------------------------------------------------------

    def _call(self, fn: Any, *args: Any) -> None:
        loop = self._loop
        if loop is not None and not loop.is_closed():
            with contextlib.suppress(RuntimeError):  # the loop closed meanwhile
                loop.call_soon_threadsafe(fn, *args)

    def _frame_from_thread(self, frame: Frame) -> None:
        self._call(self._publish, frame)

    def _event_from_thread(self, client: int | None, message: dict[str, Any]) -> None:
        self._call(self._send_event, client, message)

    # Frames to pages ----------------------------------------------------------------------

    def _publish(self, frame: Frame) -> None:
        for c in self._clients.values():
            c.pending = frame
            self._pump(c)

    def _pump(self, c: _Client) -> None:
        """Sends the client's newest frame if it has acknowledged the last one."""
        if c.in_flight is not None and time.monotonic() - c.sent_at < ACK_TIMEOUT:
            return
        frame, c.pending = c.pending, None
        if frame is None:
            return
        c.in_flight, c.sent_at = frame.id, time.monotonic()
        meta = {**frame.meta, "seq": frame.seqs.get(c.id)}
        head = json.dumps(meta).encode()
        self._spawn(self._send(c, struct.pack(">I", len(head)) + head + frame.png))

    def _acked(self, c: _Client, frame: int) -> None:
        if c.in_flight == frame:
            c.in_flight = None
            self._pump(c)

    async def _send(self, c: _Client, data: bytes | str) -> None:
        if c.ws.closed:
            return
        with contextlib.suppress(ConnectionError, RuntimeError):
            if isinstance(data, bytes):
                await c.ws.send_bytes(data)
            else:
                await c.ws.send_str(data)

    def _send_event(self, client: int | None, message: dict[str, Any]) -> None:
        text = json.dumps(message)
        targets = self._clients.values() if client is None else [self._clients.get(client)]
        for c in targets:
            if c is not None:
                self._spawn(self._send(c, text))

    def _spawn(self, coro: Any) -> None:
        task = asyncio.ensure_future(coro)
        self._tasks.add(task)
        task.add_done_callback(self._tasks.discard)

    # Routes -------------------------------------------------------------------------------

    def _check_request(self, request: web.Request) -> None:
        """Refuses other sites' pages: a foreign ``Origin``, or a non-loopback ``Host`` on
        a loopback server."""
        host = request.host.rsplit(":", 1)[0].strip("[]") if request.host else ""
        if is_loopback(self.host) and host and host not in LOOPBACK_NAMES:
            raise web.HTTPForbidden(text=f"host {request.host!r} is not this server")
        origin = request.headers.get("Origin")
        if origin is not None and urlsplit(origin).netloc != request.host:
            raise web.HTTPForbidden(text=f"origin {origin!r} is not this server")

    async def _page(self, request: web.Request) -> web.Response:
        return self._file("index.html")

    async def _static(self, request: web.Request) -> web.Response:
        name = request.match_info["name"]
        if name not in STATIC:
            raise web.HTTPNotFound()
        return self._file(name)

    def _file(self, name: str) -> web.Response:
        body = resources.files("gi.viewer").joinpath("static", name).read_bytes()
        return web.Response(
            body=body,
            content_type=STATIC[name],
            charset="utf-8",
            headers={"Cache-Control": "no-cache"},
        )

    async def _frame_png(self, request: web.Request) -> web.Response:
        assert self._loop is not None
        frame = await self._loop.run_in_executor(None, self.engine.wait_frame, REQUEST_TIMEOUT)
        if frame is None:
            raise web.HTTPServiceUnavailable(text="no frame yet")
        return web.Response(
            body=frame.png, content_type="image/png", headers={"Cache-Control": "no-store"}
        )

    async def _state(self, request: web.Request) -> web.Response:
        return web.json_response(self.engine.state())

    async def _post(self, request: web.Request) -> web.Response:
        self._check_request(request)
        route = request.path.strip("/")
        try:
            body = m.decode(await request.read())
            msgs = _post_messages(route, body, gi.methods())
            for msg in msgs:
                future = self.engine.submit(msg, wait=True)
                assert future is not None
                await asyncio.wait_for(asyncio.wrap_future(future), REQUEST_TIMEOUT)
        except gi.GiError as e:
            field = getattr(e, "field", None) or getattr(e, "setting", None)
            return web.json_response({"error": str(e), "field": field}, status=400)
        except asyncio.TimeoutError:
            return web.json_response({"error": "the renderer did not answer"}, status=503)
        return web.json_response(self.engine.state())

    async def _websocket(self, request: web.Request) -> web.WebSocketResponse:
        self._check_request(request)
        # Messages up to 1 MiB are read and refused with an error on the page; past that
        # aiohttp closes the socket (and the page reconnects).
        ws = web.WebSocketResponse(max_msg_size=1 << 20)
        await ws.prepare(request)
        c = _Client(self._next_client, ws)
        self._next_client += 1
        self._clients[c.id] = c
        self.engine.set_watchers(len(self._clients))
        try:
            await ws.send_str(json.dumps({**self.engine.state(), "type": "hello", "client": c.id}))
            frame = self.engine.latest()
            if frame is not None:
                c.pending = frame
                self._pump(c)
            async for msg in ws:
                if msg.type == WSMsgType.TEXT:
                    self._on_message(c, msg.data)
                elif msg.type == WSMsgType.BINARY:
                    self._send_event(
                        c.id, _error(m.MessageError("", "binary messages are not read"))
                    )
        finally:
            del self._clients[c.id]
            self.engine.set_watchers(len(self._clients))
        return ws

    def _on_message(self, c: _Client, text: str) -> None:
        try:
            msg = m.parse(text, gi.methods())
            if isinstance(msg, m.Ack):
                self._acked(c, msg.frame)
            else:
                self.engine.submit(msg, c.id)
        except gi.GiError as e:
            self._send_event(c.id, _error(e))


def _error(e: BaseException) -> dict[str, Any]:
    return {"type": "error", "message": str(e), "field": getattr(e, "field", None)}


def _post_messages(route: str, body: dict[str, Any], methods: list[str]) -> list[Any]:
    """The engine messages of one POST body (see the module's routes)."""
    if route == "camera":
        return [m.Camera(m.camera_fields(body, "camera"))]
    if route == "light":
        return [m.Lights(m.lights(body, "lights"))]
    if route == "object":
        return [m.Objects(m.objects(body, "objects"))]
    if route == "material":
        return [m.Materials(m.materials(body, "materials"))]
    display_keys = ("exposure", "tonemap", "aov")
    for key in body:
        if key not in (*m.SETTINGS, *display_keys, "paused"):
            raise m.MessageError(
                key,
                f"unknown setting (use: {', '.join((*m.SETTINGS, *display_keys, 'paused'))})",
            )
    out: list[Any] = []
    render = {k: v for k, v in body.items() if k in m.SETTINGS}
    if render:
        out.append(m.Settings(m.settings(render, methods)))
    if any(k in body for k in display_keys):
        out.append(m.display(body))
    if "paused" in body:
        if not isinstance(body["paused"], bool):
            raise m.MessageError("paused", "expected a boolean")
        out.append(m.Pause(body["paused"]))
    if not out:
        raise m.MessageError("settings", "no settings given")
    return out
