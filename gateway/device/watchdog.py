"""Watchdog: remote commands expire unless refreshed in time (time from the gateway clock).

Real devices all have such a rule (Dachs PIN within 10 min, Lambda 5 min, Belimo 120 s); the map
declares it as data (WatchdogRule) and this class keeps the timer. It never reads wall time, so
lock-step tests are deterministic.
"""
from __future__ import annotations

from gateway.maps.model import WatchdogRule


class Watchdog:
    """Armed by the first refreshing write; `tick(t)` returns True once when it expires."""

    def __init__(self, rule: WatchdogRule) -> None:
        self.rule = rule
        self.timeout_s = rule.timeout_s
        self.last_refresh: float | None = None
        self.expired = False

    def refreshes(self, point: str) -> bool:
        return "*" in self.rule.refresh_on or point in self.rule.refresh_on

    def refresh(self, t: float) -> bool:
        """Restart the timer; returns True if this recovered an expired watchdog."""
        recovered = self.expired
        self.last_refresh, self.expired = t, False
        return recovered

    def tick(self, t: float) -> bool:
        if self.expired or self.last_refresh is None:
            return False
        if t - self.last_refresh >= self.timeout_s:
            self.expired = True
            self.last_refresh = None
            return True
        return False
