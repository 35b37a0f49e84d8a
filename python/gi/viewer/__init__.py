"""An interactive viewer in the browser: ``gi view SCENE`` and :func:`gi.view`.

A local web server (aiohttp) renders the scene with one :class:`gi.Renderer` and sends
its frames to the page over a WebSocket; the page orbits, pans, zooms and flies the camera,
drags lights and objects and changes the method and display from a side panel. The server
binds 127.0.0.1 unless told otherwise. Routes, messages and their checks:
:mod:`gi.viewer.server`, :mod:`gi.viewer.messages`.

Needs ``pip install 'gi[view]'`` (aiohttp).
"""

from __future__ import annotations

import asyncio
import atexit
import contextlib
import signal
import sys
import threading
import warnings
import webbrowser
from typing import Any

import gi
from gi._checks import exposure_setting
from gi.display import check_tonemap

INSTALL_HINT = "the viewer needs aiohttp: pip install 'gi[view]'"


def _server_module() -> Any:
    try:
        from gi.viewer import server
    except ImportError as e:
        if e.name is not None and e.name.split(".")[0] == "aiohttp":
            raise gi.SettingError(INSTALL_HINT) from None
        raise
    return server


def _display(exposure: float, tonemap: str) -> Any:
    from gi.viewer.engine import DisplayState

    try:
        check_tonemap(tonemap)
    except ValueError as e:
        raise gi._checks.setting_error("tonemap", str(e)) from None
    return DisplayState(exposure_setting(exposure), tonemap)


def warn_if_exposed(host: str) -> str | None:
    """The warning for a server reachable from other machines (``None`` on loopback)."""
    if _server_module().is_loopback(host):
        return None
    return (
        f"serving on {host}: anyone who can reach this address can see the scene and drive"
        " the renderer (there is no password); use the default 127.0.0.1 unless you mean it"
    )


def serve(
    scene: gi.Scene,
    method: str,
    options: dict[str, Any],
    *,
    host: str = "127.0.0.1",
    port: int = 0,
    open_browser: bool = True,
    exposure: float = 0.0,
    tonemap: str = "clip",
    env_dir: str | None = None,
) -> int:
    """Runs the viewer in this thread until SIGINT or SIGTERM (the ``gi view`` command);
    prints the URL to stderr. ``env_dir``: the folder whose .hdr/.exr images the
    Environment panel offers."""
    server_module = _server_module()
    display = _display(exposure, tonemap)
    warning = warn_if_exposed(host)
    if warning:
        print(f"gi view: warning: {warning}", file=sys.stderr)

    async def main() -> None:
        server = server_module.ViewerServer(
            scene, method, options, host=host, port=port, display=display, env_dir=env_dir
        )
        stop = asyncio.Event()
        loop = asyncio.get_running_loop()
        for sig in (signal.SIGINT, signal.SIGTERM):
            loop.add_signal_handler(sig, stop.set)
        try:
            url = await server.start()
            print(f"gi view: {url}  (Ctrl-C stops)", file=sys.stderr, flush=True)
            if open_browser:
                loop.run_in_executor(None, webbrowser.open, url)
            await stop.wait()
        finally:
            await server.stop()

    asyncio.run(main())
    return 0


class _Background:
    """A viewer served from its own thread and event loop (:func:`view`)."""

    def __init__(self, make: Any) -> None:
        self._make = make
        self._ready = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._stop: asyncio.Event | None = None
        self._error: BaseException | None = None
        self.url = ""
        self._thread = threading.Thread(target=self._run, name="gi-view-server", daemon=True)

    def start(self) -> str:
        self._thread.start()
        self._ready.wait()
        if self._error is not None:
            raise self._error
        return self.url

    def _run(self) -> None:
        async def main() -> None:
            self._loop = asyncio.get_running_loop()
            self._stop = asyncio.Event()
            try:
                server = self._make()
                self.url = await server.start()
            except BaseException as e:
                self._error = e
                self._ready.set()
                return
            self._ready.set()
            try:
                await self._stop.wait()
            finally:
                await server.stop()

        asyncio.run(main())

    def stop(self) -> None:
        if self._loop is not None and self._stop is not None and not self._loop.is_closed():
            with contextlib.suppress(RuntimeError):
                self._loop.call_soon_threadsafe(self._stop.set)
        self._thread.join(5.0)


_running: dict[str, _Background] = {}


def view(
    scene: gi.Scene | str,
    method: str = gi.DEFAULT_METHOD,
    *,
    host: str = "127.0.0.1",
    port: int = 0,
    open_browser: bool = False,
    exposure: float = 0.0,
    tonemap: str = "clip",
    env_dir: str | None = None,
    **options: Any,
) -> str:
    """Starts the viewer of ``scene`` (a :class:`gi.Scene` or what :func:`gi.load_scene`
    takes) in a background thread and returns its URL; in Jupyter the page is shown inline.
    ``options`` are the keywords of :class:`gi.Renderer` (``size=(320, 240)``,
    ``photons=20_000``, ...); ``port=0`` picks a free port; ``env_dir``: a folder whose
    .hdr/.exr images the Environment panel offers. :func:`stop` ends it.

    >>> url = gi.view("cornell", size=(320, 240))
    """
    server_module = _server_module()
    if isinstance(scene, str):
        scene = gi.load_scene(scene)
    display = _display(exposure, tonemap)
    warning = warn_if_exposed(host)
    if warning:
        warnings.warn(warning, stacklevel=2)
    background = _Background(
        lambda: server_module.ViewerServer(
            scene, method, options, host=host, port=port, display=display, env_dir=env_dir
        )
    )
    url = background.start()
    _running[url] = background
    if open_browser:
        webbrowser.open(url)
    _show_inline(url)
    return url


def stop(url: str | None = None) -> None:
    """Stops the viewer at ``url`` started by :func:`view` (``None``: every one)."""
    for u in [url] if url is not None else list(_running):
        background = _running.pop(u, None)
        if background is not None:
            background.stop()


# Viewers still running at exit stop first: a frame under way is cancelled before gi waits
# for the GPU (atexit runs this before gi's own handler, registered earlier).
atexit.register(stop)


def _show_inline(url: str) -> None:
    """Shows the page in the notebook when running in a Jupyter kernel."""
    ipython = sys.modules.get("IPython")
    shell = ipython.get_ipython() if ipython is not None else None  # type: ignore[attr-defined]
    if shell is None or "IPKernelApp" not in getattr(shell, "config", {}):
        return
    from IPython.display import IFrame, display

    display(IFrame(url, width="100%", height=560))
