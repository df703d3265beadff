"""A house of a district as the grid sees it: loaded with the district's overrides, fed the grid's
temperatures at its node, and its substation's meters turned into the grid's `Draw`.

This is the one coupling of a house to the grid (district/grid.py): the house federate uses it
across processes (district/federation/house_federate.py), the PHIL grid side in one process for
the district's other houses (phil/grid.py). Each exchange step the house is set the supply and
return temperature the grid published at its node, steps, and reports what its substation's
meters counted over the step: grid water taken and given back while extracting and while feeding
in, and the enthalpy given back, which is the enthalpy taken (taken water x the published
temperature) less the metered heat. The grid therefore books exactly the heat the house's
ledger booked (`fuel_substation` - `building_substation`).
"""
from __future__ import annotations

from typing import Any

from district.grid import Draw
from plant.water import CP

METERS = ("substation.M_extracted", "substation.E_extracted", "substation.M_fed_in", "substation.E_fed_in")
GRID_INPUTS = ("substation.T_grid_sup", "substation.T_grid_ret")


def exchange(before: list[float], after: list[float], T_sup: float, T_ret: float) -> list[float]:
    """[M_extracted, H_extracted_back, M_fed_in, H_fed_in_back] over a step from the meters."""
    M_e, Q_e, M_f, Q_f = (a - b for a, b in zip(after, before))
    return [M_e, M_e * CP * T_sup - Q_e, M_f, M_f * CP * T_ret + Q_f]


def load(district: Any, entry: Any, *, start: str | None = None, controller: str | None = None,
         overrides: dict | None = None) -> Any:
    """The house of a district entry with the district's overrides (and `overrides` on top, e.g.
    a type day), its grid temperatures live inputs from now on (the grid's, not the file's)."""
    from plant.house import load_house

    if controller is None:
        controller = "external" if entry.controller == "external" else "rule_based"
    house = load_house(entry.file, start=start or district.start, controller=controller,
                       overrides={**entry.house_overrides(), **(overrides or {})})
    for name in GRID_INPUTS:
        house.set(name, house.get(name))
    return house


class Member:
    """A district house stepped in the same process as its grid (the caller steps the grid)."""

    def __init__(self, name: str, node: str, house: Any) -> None:
        self.name, self.node, self.house = name, node, house

    def step(self, dt: float, T_sup: float, T_ret: float) -> Draw:
        """Step the house by dt at the grid's published temperatures; its draw over the step."""
        house = self.house
        house.set(GRID_INPUTS[0], T_sup)
        house.set(GRID_INPUTS[1], T_ret)
        before = [house.get(m) for m in METERS]
        house.step(dt)
        return Draw(*exchange(before, [house.get(m) for m in METERS], T_sup, T_ret))

    def heat_from_grid(self) -> float:
        """J the house's ledger booked from the grid since the start (extracted less fed in)."""
        L = self.house.ledger()
        return L.get("fuel_substation", 0.0) - L.get("building_substation", 0.0)
