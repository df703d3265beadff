"""The district grid as the simulated side of a PHIL run: a house's node of a district file's grid,
whose supply temperature and differential pressure the grid emulator bench follows, and whose
draw is the lab substation's measured grid flow and return, with the district's other houses
simulated drawing at their nodes.

In a district PHIL run (the issue's "for the district the grid"; docs/phil.md) the house's
substation and storage are the lab's hardware and the grid is simulated: `GridSide` is the
district's grid (district/grid.py Grid, the district file's plant, pipes and nodes,
unchanged) with the PHIL house at its node. Each step it publishes the supply- and return-line
temperature at the node (the grid's, at the step's start) and the differential pressure there;
the loop sends the supply temperature and the differential pressure to the grid emulator, and
feeds back the measured grid flow through the lab's substation (`grid.m_flow`, kg/s) and the
measured return from it (`grid.T_return`). Over the step the grid takes that draw as a district
house's metered exchange (district/grid.py Draw: water taken at the published supply
temperature, given back at the measured return), so the heat the grid gives the house is
    Q_flow = m cp (T_sup published - T_return measured).

The other houses (`others="all"`, the default; `twin phil --others none`: only the PHIL house
draws) are the twin's own simulated houses of the district file, each with its simulated
substation and the district's overrides, coupled to the grid as in a district run
(district/member.py, the house federate's coupling, here in one process): each step, in
lock-step with the PHIL house at the loop's step, each is set the temperatures the grid
published at its node, steps, and its substation's meters are its draw. They run their
built-in rules (no external controller is attached in a PHIL run) on the PHIL house's profiles
(its start and type day). The grid's ledger (plant heat, pipe losses, heat to each house, stored
heat) closes as in a district run; the report gives the heat the grid booked to each house
beside what that house's substation metered.

Differential pressure (stated assumption; the district file has no pump head): the plant's pump
holds DP_PLANT across the plant's connection; the node's differential pressure is that less the
supply and return pipes' drops on the path at the whole district's flows (the grid's
Darcy-Weisbach drops at this step's flows, signed: where feed-in beyond a pipe sends its water
back to the plant, the drop raises the node's pressure difference). With the lab's DN100 pipes
and 0.2 kg/s substations the drops are a few Pa: at sf1 the node moves about +-5 Pa as the
substations open and close (0.2 kg/s net through the first pipe), below the grid emulator's
1 mbar sensor resolution. The supply temperature moves with the pipes' delay and losses at all
houses' flows (after a rest the pipe's standing water arrives first, then the plant's 70 degC).

Cost: the other houses' steps are tens of microseconds each; the grid's step (pure Python and
numpy over the pipes' parcels) is the cost, 0.3-0.8 ms median (report `grid.step_ms`).

`HouseOnGrid` is the PHIL house and the grid side as one plant for the loop (get/set/step and
the rest of the house's face): signals `grid.*` are the grid side's, all others the house's.
"""
from __future__ import annotations

import dataclasses
import math
import time
from typing import Any

import numpy as np

from district.declaration import load_district
from district.grid import Draw, Grid, _dp
from district.member import Member, load
from plant.errors import ConfigError
from plant.water import CP

#: Pa the plant's pump holds across its connection (assumed: 1 bar)
DP_PLANT = 1.0e5
#: s: while nothing flows the grid is stepped this seldom (the district's exchange step)
IDLE_STEP = 60.0

#: --others: the district's other houses simulated on the grid, or only the PHIL house drawing
OTHERS = ("all", "none")

INPUTS = ("grid.m_flow", "grid.T_return")
OUTPUTS = ("grid.T_sup", "grid.T_ret", "grid.dp", "grid.Q_flow", "grid.E", "grid.Q_plant", "grid.m_plant")


class GridSide:
    """The district's grid with the PHIL house and the other houses drawing (see the module text)."""

    def __init__(self, district: str, house: str, dp_plant: float = DP_PLANT, others: str = "all",
                 start: str | None = None, overrides: dict | None = None) -> None:
        d = load_district(district)
        entry = next((h for h in d.houses if h.name == house), None)
        if entry is None:
            raise ConfigError(f"{d.path}: no house {house!r} for the PHIL grid; houses: "
                              + ", ".join(h.name for h in d.houses))
        if others not in OTHERS:
            raise ConfigError(f"--others {others!r}: allowed {' or '.join(OTHERS)} (all: the district's "
                              "other houses simulated on the grid; none: only the PHIL house draws)")
        self.district, self.house, self.node = d.name, house, entry.node
        # the others run their built-in rules: no external controller is attached in a PHIL run
        self.members = {e.name: Member(e.name, e.node, load(d, e, start=start, controller="rule_based",
                                                          overrides=overrides))
                        for e in d.houses if others == "all" and e.name != house}
        attach = {house: entry.node, **{m.name: m.node for m in self.members.values()}}
        self.grid = Grid(dataclasses.replace(d.grid, attach=attach))
        self.dp_plant = dp_plant
        self.idle = 0.0             # s not yet stepped while nothing flowed
        self.heat = dict.fromkeys(attach, 0.0)     # J the grid gave each house (net of feed-in)
        self.step_s: list[float] = []              # wall time of each step: the others and the grid
        self.values = {name: 0.0 for name in INPUTS + OUTPUTS}
        self.values["grid.T_return"] = self.grid.temperatures(house)[1]
        self._publish()

    def _publish(self) -> None:
        """Every house's node temperatures, and the PHIL house's node values, at this instant."""
        self.published = {h: self.grid.temperatures(h) for h in self.grid.houses}
        T_sup, T_ret = self.published[self.house]
        # signed: a pipe whose flow runs back to the plant (feed-in beyond it) raises the node's
        # differential pressure by its drops instead of lowering it
        drops = np.array([2.0 * math.copysign(_dp(p, f), f)
                          for p, f in zip(self.grid.spec.pipes, self.grid.flow)])
        path = float(self.grid.beyond[:, self.grid.index[self.node]] @ drops) if len(drops) else 0.0
        self.values.update({"grid.T_sup": T_sup, "grid.T_ret": T_ret, "grid.dp": self.dp_plant - path})

    def step(self, dt: float) -> None:
        """The other houses step at their published temperatures; the PHIL house drew the measured
        flow over dt at the published supply temperature and gave it back at the measured return.
        While no house draws the grid only loses heat (exactly per step, plant/grid/pipe.py): it
        is stepped once per IDLE_STEP (the unpaced pre-run of a day takes 720 grid steps
        instead of 43,200)."""
        began = time.perf_counter()
        draws = {n: m.step(dt, *self.published[n]) for n, m in self.members.items()}
        draws = {n: d for n, d in draws.items() if d.M_extracted or d.M_fed_in}
        m = max(self.values["grid.m_flow"], 0.0)
        Q = 0.0
        if m > 0.0:
            T_return = self.values["grid.T_return"]
            draws[self.house] = Draw(M_extracted=m * dt, H_extracted_back=m * dt * CP * T_return)
            Q = m * CP * (self.published[self.house][0] - T_return)
        self.values.update({"grid.Q_flow": Q, "grid.E": self.values["grid.E"] + Q * dt})
        if not draws and self.idle + dt < IDLE_STEP:
            self.idle += dt
            self.step_s.append(time.perf_counter() - began)
            return
        if draws and self.idle > 0.0:
            self.grid.step(self.idle, {}, {})
        span, self.idle = (dt if draws else self.idle + dt), 0.0
        self.grid.step(span, draws, self.published)
        for n, d in draws.items():
            T_sup, T_ret = self.published[n]
            self.heat[n] += d.M_extracted * CP * T_sup - d.H_extracted_back + d.M_fed_in * CP * T_ret - d.H_fed_in_back
        self.values.update({"grid.Q_plant": self.grid.Q_plant, "grid.m_plant": self.grid.m_plant})
        self._publish()
        self.step_s.append(time.perf_counter() - began)

    def ledger(self) -> dict[str, float]:
        return self.grid.ledger()

    def report(self) -> dict[str, Any]:
        """Where the house sits, the grid's ledger [kWh] (closure: a fraction), the heat the grid
        gave each house against what that house's substation metered, and the step's wall time."""
        L = self.ledger()
        houses = {self.house: {"grid_kWh": self.heat[self.house] / 3.6e6,
                               "metered_kWh": self.values["grid.E"] / 3.6e6}}
        for n, m in self.members.items():
            own = m.house.ledger()
            houses[n] = {"grid_kWh": self.heat[n] / 3.6e6, "metered_kWh": m.heat_from_grid() / 3.6e6,
                         "closure": float(own["closure"])}
        cost = np.array(self.step_s) * 1e3
        return {"district": self.district, "node": self.node, "others": list(self.members),
                **{f"{k}_kWh": float(v) / 3.6e6 for k, v in L.items() if k not in ("residual", "closure")},
                "closure": float(L["closure"]), "houses": houses,
                "step_ms": {"median": float(np.median(cost)) if len(cost) else None,
                            "p99": float(np.percentile(cost, 99)) if len(cost) else None}}


class HouseOnGrid:
    """A PHIL house and its simulated grid side, stepped together (grid after the house)."""

    boundary_signals = INPUTS + OUTPUTS

    def __init__(self, house: Any, grid: GridSide) -> None:
        self.house, self.grid = house, grid

    def get(self, name: str) -> float:
        return float(self.grid.values[name]) if name.startswith("grid.") else self.house.get(name)

    def set(self, name: str, value: float) -> None:
        if not name.startswith("grid."):
            self.house.set(name, value)
        elif name in INPUTS:
            self.grid.values[name] = float(value)
        else:
            raise ConfigError(f"grid: {name!r} is not an input of the PHIL grid; inputs: {', '.join(INPUTS)}")

    def step(self, dt: float) -> None:
        self.house.step(dt)
        self.grid.step(dt)

    def boundary_report(self) -> dict[str, Any]:
        return {"grid": self.grid.report()}

    def __getattr__(self, name: str) -> Any:       # t, ledger, catalogue ...: the house's
        return getattr(self.house, name)
