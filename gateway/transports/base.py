"""Transport: the small base every protocol server implements (start, stop, name)."""
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

    def __enter__(self) -> "Transport":
        self.start()
        return self

    def __exit__(self, *exc: object) -> None:
        self.stop()
