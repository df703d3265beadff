"""The district grid as the simulated side of a PHIL run: a house's node of a district file's grid,
whose supply temperature and differential pressure the grid emulator bench follows, and whose
draw is the lab substation's measured grid flow and return.

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
    Q_flow = m cp (T_sup published - T_return measured)
and the grid's ledger (plant heat, pipe losses, heat to the house, stored heat) closes as in a
district run.

Differential pressure (stated assumption; the district file has no pump head): the plant's pump
holds DP_PLANT across the plant's connection; the node's differential pressure is that less the
supply and return pipes' drops on the path (the grid's Darcy-Weisbach drops at this step's
flows). The other houses of the district are not simulated in a PHIL run: only the PHIL house
draws. With the lab's DN100 pipes and one substation's flow the drops are a few Pa, so the node's
differential pressure stays at the plant's; the supply temperature moves with the pipes' delay
and losses (the water that stood in the pipe while the substation rested arrives first).

`HouseOnGrid` is the PHIL house and the grid side as one plant for the loop (get/set/step and
the rest of the house's face): signals `grid.*` are the grid side's, all others the house's.
"""
from __future__ import annotations

import dataclasses
from typing import Any

import numpy as np

from district.declaration import load_district
from district.grid import Draw, Grid, _dp
from plant.errors import ConfigError
from plant.water import CP

#: Pa the plant's pump holds across its connection (assumed: 1 bar)
DP_PLANT = 1.0e5
#: s: while nothing flows the grid is stepped this seldom (the district's exchange step)
IDLE_STEP = 60.0

INPUTS = ("grid.m_flow", "grid.T_return")
OUTPUTS = ("grid.T_sup", "grid.T_ret", "grid.dp", "grid.Q_flow", "grid.E", "grid.Q_plant", "grid.m_plant")


class GridSide:
    """The district's grid with one house drawing at its node (see the module text)."""

    def __init__(self, district: str, house: str, dp_plant: float = DP_PLANT) -> None:
        d = load_district(district)
        entry = next((h for h in d.houses if h.name == house), None)
        if entry is None:
            raise ConfigError(f"{d.path}: no house {house!r} for the PHIL grid; houses: "
                              + ", ".join(h.name for h in d.houses))
        self.district, self.house, self.node = d.name, house, entry.node
        self.grid = Grid(dataclasses.replace(d.grid, attach={house: entry.node}))
        self.dp_plant = dp_plant
        self.idle = 0.0             # s not yet stepped while nothing flowed
        self.values = {name: 0.0 for name in INPUTS + OUTPUTS}
        self.values["grid.T_return"] = self.grid.temperatures(house)[1]
        self._publish()

    def _publish(self) -> None:
        T_sup, T_ret = self.grid.temperatures(self.house)
        self.published = (T_sup, T_ret)
        drops = np.array([2.0 * _dp(p, f) for p, f in zip(self.grid.spec.pipes, self.grid.flow)])
        path = float(self.grid.beyond[:, self.grid.index[self.node]] @ drops) if len(drops) else 0.0
        self.values.update({"grid.T_sup": T_sup, "grid.T_ret": T_ret, "grid.dp": self.dp_plant - path})

    def step(self, dt: float) -> None:
        """The house drew the measured flow over dt at the published supply temperature and gave
        it back at the measured return. While nothing flows the grid only loses heat (exactly
        per step, plant/grid/pipe.py): it is stepped once per IDLE_STEP (the unpaced pre-run of
        a day takes 720 grid steps instead of 43,200)."""
        m = max(self.values["grid.m_flow"], 0.0)
        if m == 0.0 and self.idle + dt < IDLE_STEP:
            self.idle += dt
            self.values["grid.Q_flow"] = 0.0
            return
        if self.idle > 0.0:
            idle, self.idle = self.idle + (dt if m == 0.0 else 0.0), 0.0
            self.grid.step(idle, {}, {})
            self._publish()
            if m == 0.0:
                self.values.update({"grid.Q_flow": 0.0, "grid.Q_plant": self.grid.Q_plant,
                                    "grid.m_plant": self.grid.m_plant})
                return
        M = m * dt
        draw = Draw(M_extracted=M, H_extracted_back=M * CP * self.values["grid.T_return"])
        Q = m * CP * (self.published[0] - self.values["grid.T_return"])
        self.grid.step(dt, {self.house: draw}, {self.house: self.published})
        self.values.update({"grid.Q_flow": Q, "grid.E": self.values["grid.E"] + Q * dt,
                            "grid.Q_plant": self.grid.Q_plant, "grid.m_plant": self.grid.m_plant})
        self._publish()

    def ledger(self) -> dict[str, float]:
        return self.grid.ledger()

    def report(self) -> dict[str, Any]:
        """Where the house sits and the grid's ledger [kWh] (closure: a fraction)."""
        L = self.ledger()
        return {"district": self.district, "node": self.node,
                **{f"{k}_kWh": float(v) / 3.6e6 for k, v in L.items() if k not in ("residual", "closure")},
                "closure": float(L["closure"])}


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
