"""The event loop the servers run on: asyncio's own, or uvloop's when installed (the only uvloop
import), and the thread a server runs it in (ServerThread).

uvloop (`pip install -e ".[fast]"`) is a libuv-based drop-in for asyncio's loop; the servers'
threads create their loops with `asyncio.new_event_loop()`, so installing uvloop's policy before
they start is all it takes. benchmarks/gateway_latency.py measures what it changes.
"""
from __future__ import annotations

import asyncio
import threading
from collections.abc import Awaitable, Callable
from typing import Any

from plant.errors import ConfigError, TransportError

CHOICES = ("auto", "asyncio", "uvloop")


def install(choice: str = "auto") -> str:
    """Make new event loops `choice`'s ("auto": uvloop if installed); returns the loop in use."""
    if choice not in CHOICES:
        raise ConfigError(f"event loop {choice!r}: unknown; use one of {', '.join(CHOICES)}")
    if choice == "asyncio":
        asyncio.set_event_loop_policy(None)
        return "asyncio"
    try:
        import uvloop
    except ImportError:
        if choice == "uvloop":
            raise ConfigError('event loop uvloop: not installed; pip install -e ".[fast]" '
                              "or use --loop asyncio") from None
        return "asyncio"
    asyncio.set_event_loop_policy(uvloop.EventLoopPolicy())
    return "uvloop"


class ServerThread:
    """A server's event loop in a daemon thread of its own.

    start(open, where, hint) makes a new event loop in the thread, runs `open()` in it and returns
    once that has returned, then the loop runs until stop(); a failure of open(), or no start
    within 10 s, is raised in the caller's thread as a TransportError naming `where` (and `hint`).
    """

    def __init__(self, name: str) -> None:
        self.name = name
        self.loop: asyncio.AbstractEventLoop | None = None
        self._thread: threading.Thread | None = None
        self._ready = threading.Event()
        self._error: BaseException | None = None

    @property
    def running(self) -> bool:
        return self.loop is not None and self.loop.is_running()

    def start(self, open: Callable[[], Awaitable[Any]], where: str, hint: str) -> None:
        self._thread = threading.Thread(target=self._run, args=(open,), name=self.name, daemon=True)
        self._thread.start()
        if not self._ready.wait(10):
            raise TransportError(f"{where}: server did not start within 10 s")
        if self._error:
            raise TransportError(f"{where}: cannot serve ({self._error}); {hint}")

    def call(self, coro: Awaitable[Any], timeout: float) -> Any:
        """Run `coro` in the loop from another thread; its result, waiting at most `timeout` s."""
        return asyncio.run_coroutine_threadsafe(coro, self.loop).result(timeout)

    def stop(self) -> None:
        """Stop the loop and join the thread (at most 5 s)."""
        self.loop.call_soon_threadsafe(self.loop.stop)
        if self._thread:
            self._thread.join(5)

    def _run(self, open: Callable[[], Awaitable[Any]]) -> None:
        loop = asyncio.new_event_loop()
        self.loop = loop
        try:
            loop.run_until_complete(open())
        except BaseException as exc:  # reported to start() in the caller's thread
            self._error = exc
            self._ready.set()
            loop.close()
            return
        self._ready.set()
        try:
            loop.run_forever()
        finally:
            loop.close()
