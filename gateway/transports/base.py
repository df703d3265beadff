"""Transport: the one protocol every bus server implements (start, stop, wake, name).

A new transport is a module with a Transport subclass and one line in registry.py; the runtime
adds any registered one the same way: `Runtime.add(name, **options)`."""
from __future__ import annotations

from abc import ABC, abstractmethod


class Transport(ABC):
    """Serves Devices on one bus. Turns frames into Device calls and Refusals into answers;
    never validates values or touches plant state itself."""

    name: str = "transport"

    @abstractmethod
    def start(self) -> None:
        """Begin serving; returns once the bus is ready (raises TransportError otherwise)."""

    @abstractmethod
    def stop(self) -> None:
        """Stop serving and release the port; safe to call twice."""

    def wake(self) -> None:
        """Called after every plant step: a transport with time-driven output (CANopen's
        heartbeat, SYNC-driven PDOs) sends it here; a request-answer bus has nothing to do."""

    @classmethod
    def hooks(cls, runtime) -> dict:
        """The constructor options a runtime supplies itself (an event sink, its plant clock);
        the caller's options come on top of them."""
        return {}

    def __enter__(self) -> "Transport":
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
