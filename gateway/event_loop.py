"""The event loop the servers run on: asyncio's own, or uvloop's when installed (the only uvloop import).

uvloop (`pip install -e ".[fast]"`) is a libuv-based drop-in for asyncio's loop; the servers'
threads create their loops with `asyncio.new_event_loop()`, so installing uvloop's policy before
they start is all it takes. benchmarks/gateway_latency.py measures what it changes.
"""
from __future__ import annotations

import asyncio

from plant.errors import ConfigError

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
