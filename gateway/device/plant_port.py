"""PlantPort: the one lock around the house, shared by every device and transport thread.

House calls are not thread-safe, while Modbus TCP, RTU and CANopen serve from their own threads.
Every plant access of the gateway goes through one PlantPort, so the lock sits in one place.
"""
from __future__ import annotations

import threading

from plant.protocol import Plant


class PlantPort:
    """Serialised access to a house: get/set/release/step under one re-entrant lock."""

    def __init__(self, house: Plant) -> None:
        self.house = house
        self.lock = threading.RLock()

    @property
    def t(self) -> float:
        with self.lock:
            return float(self.house.t)

    def get(self, name: str) -> float:
        with self.lock:
            return float(self.house.get(name))

    def set(self, name: str, value: float) -> None:
        with self.lock:
            self.house.set(name, value)

    def release(self, name: str) -> None:
        with self.lock:
            self.house.release(name)

    def step(self, dt: float) -> None:
        with self.lock:
            self.house.step(dt)

    def has(self, name: str) -> bool:
        with self.lock:
            return name in self.house.catalogue
