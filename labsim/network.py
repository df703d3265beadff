"""labsim hydraulics: a pressure-driven two-node network (supply header S, return header R).

Branches between R and S (flows in kg/s, pressures in Pa, dP = p_S - p_R):
  * the storage, the hydraulic separator: a plain resistance, q_st = sign(dP) sqrt(|dP| / r_st)
    (q_st > 0: S -> top of the tank, bottom -> R, charging);
  * pumped branches (generators R -> S, consumers S -> R): a running pump is set to its target
    flow q_t against a design head dp_d (pump curve and branch resistance lumped), so against a
    counter-pressure D (the rise its branch must make) it delivers q = q_t sqrt(max(0, 1 - D/dp_d));
  * a generator whose pump stands is a resistance r_idle behind a check valve: a flap
    (check="flap") stops only reverse flow, a spring-loaded valve (check="spring") also needs
    the opening pressure dp_crack before it lets water through forward (R -> S).
Mass balance at S gives one equation in dP, monotone in dP, solved by Brent's method.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from scipy.optimize import brentq


@dataclass
class Branch:
    name: str
    dp_design: float              # Pa: head at the target flow of a running pump
    r_idle: float = math.inf      # Pa/(kg/s)^2 with the pump standing (generators)
    check: str = "flap"           # none | flap | spring
    dp_crack: float = 0.0         # Pa, spring-loaded check valve
    consumer: bool = False        # S -> R (else R -> S)
    q_target: float = 0.0         # kg/s, 0 = pump off
    q_max: float = math.inf       # kg/s, e.g. a mixing valve passes at most the circuit's flow

    def flow(self, dP: float) -> float:
        """Flow in the branch's own direction for the header difference dP = p_S - p_R."""
        rise = -dP if self.consumer else dP  # pressure the branch must climb
        if self.q_target > 0.0:
            return min(self.q_max, self.q_target * math.sqrt(max(0.0, 1.0 - rise / self.dp_design)))
        if math.isinf(self.r_idle):
            return 0.0
        drive = -rise - (self.dp_crack if self.check == "spring" else 0.0)
        if drive > 0.0:
            return math.sqrt(drive / self.r_idle)
        if self.check == "none" and rise > 0.0:
            return -math.sqrt(rise / self.r_idle)
        return 0.0


class Network:
    def __init__(self, branches: list[Branch], r_storage: float):
        self.branches = {b.name: b for b in branches}
        self.r_st = r_storage
        self.dP = 0.0

    def storage_flow(self, dP: float) -> float:
        return math.copysign(math.sqrt(abs(dP) / self.r_st), dP)

    def _balance(self, dP: float) -> float:
        s = 0.0
        for b in self.branches.values():
            q = b.flow(dP)
            s += -q if b.consumer else q
        return s - self.storage_flow(dP)

    def solve(self) -> dict[str, float]:
        """Flows {branch: q, "storage": q_st} for the current pump targets."""
        lo, hi = -2e5, 2e5
        self.dP = brentq(self._balance, lo, hi, xtol=1e-6, rtol=1e-10) if self._balance(0.0) != 0.0 else 0.0
        out = {n: b.flow(self.dP) for n, b in self.branches.items()}
        out["storage"] = self.storage_flow(self.dP)
        return out


__all__ = ["Branch", "Network"]
