"""The one unit table: each unit's kind and its affine conversion to the unit the code uses.

    convert(20.0, "degC", "K")            -> 293.15
    convert(12.0, "l/min", "kg/s")        -> 0.2   (water: plant/water.py's RHO)
    factors("W", "kW")                    -> (0.001, 0.0): kW = 0.001 * W + 0.0

Code holds SI: temperatures in degC, temperature differences in K, flows in kg/s, powers in W,
energies in J, fractions in 1, voltages in V, times in s (run-hour counters in h).  Each unit
here has a kind and (factor, offset) with `value_in_the_kind's_SI_unit = value * factor + offset`;
two units convert when their kinds match.

  * Volume flows (l/min, l/h, m3/h, ...) are water mass flows: they convert to kg/s with the one
    water density of plant/water.py (RHO = 1000 kg/m3), as every meter of the plant measures water.
  * "K" is an absolute temperature at the edges (FMUs, a pump reporting kelvin, a lab column), so
    K -> degC subtracts 273.15.  A temperature difference converts with `difference=True`,
    which drops the offsets (1 K of difference = 1 degC of difference).
  * SPANS holds the one convention that is not a unit conversion: a 0-10 V control voltage shown
    as 0-100 % (device maps); `convert(..., span=True)` allows it.

Used by the device maps' codec, recordings and columns files, diagnosis, FMU bindings and the CLI.
"""
from __future__ import annotations

from fractions import Fraction
from functools import cache
from typing import NamedTuple

from .errors import ConfigError, closest
from .water import RHO


class Unit(NamedTuple):
    kind: str
    factor: float  # value in the kind's SI unit = value * factor + offset
    offset: float


#: kind -> the unit the code holds it in
SI: dict[str, str] = {
    "temperature": "degC", "temperature difference": "K", "mass flow": "kg/s", "power": "W",
    "energy": "J", "fraction": "1", "voltage": "V", "time": "s", "irradiance": "W/m2",
    "conductance": "W/K", "heat capacity": "J/K", "length": "m", "volume": "m3", "pressure": "Pa",
    "mass": "kg",
}

_EXACT: dict[str, tuple[Fraction, Fraction]] = {}  # factor and offset as exact fractions


def _table(rows: dict[str, tuple]) -> dict[str, Unit]:
    out = {}
    for name, (k, factor, *offset) in rows.items():
        f, o = Fraction(factor), Fraction(offset[0] if offset else 0)
        _EXACT[name] = (f, o)
        out[name] = Unit(k, float(f), float(o))
    return out


_RHO = Fraction(RHO)  # kg/m3
UNITS: dict[str, Unit] = _table({
    # temperature (absolute); "K" also names temperature differences, see the module text
    "degC": ("temperature", 1), "°C": ("temperature", 1), "C": ("temperature", 1),
    "K": ("temperature", 1, Fraction("-273.15")), "degF": ("temperature", Fraction(5, 9), Fraction(-160, 9)),
    # mass flow; volume flows of water through RHO
    "kg/s": ("mass flow", 1), "kg/h": ("mass flow", Fraction(1, 3600)),
    "l/s": ("mass flow", _RHO / 1000), "l/min": ("mass flow", _RHO / 60000),
    "l/h": ("mass flow", _RHO / 3600000), "m3/h": ("mass flow", _RHO / 3600),
    "m³/h": ("mass flow", _RHO / 3600), "m3/s": ("mass flow", _RHO),
    "W": ("power", 1), "kW": ("power", 1000), "MW": ("power", 10**6),
    "J": ("energy", 1), "kJ": ("energy", 1000), "Wh": ("energy", 3600), "kWh": ("energy", 3600000),
    "MWh": ("energy", 3600000000),
    "1": ("fraction", 1), "": ("fraction", 1), "-": ("fraction", 1), "%": ("fraction", Fraction(1, 100)),
    "V": ("voltage", 1), "mV": ("voltage", Fraction(1, 1000)),
    "s": ("time", 1), "min": ("time", 60), "h": ("time", 3600),
    "W/m2": ("irradiance", 1),
    "W/K": ("conductance", 1), "kW/K": ("conductance", 1000),
    "J/K": ("heat capacity", 1), "kJ/K": ("heat capacity", 1000), "kWh/K": ("heat capacity", 3600000),
    "m": ("length", 1), "cm": ("length", Fraction(1, 100)), "mm": ("length", Fraction(1, 1000)),
    "m3": ("volume", 1), "l": ("volume", Fraction(1, 1000)),
    "Pa": ("pressure", 1), "kPa": ("pressure", 1000), "bar": ("pressure", 100000),
    "kg": ("mass", 1), "t": ("mass", 1000),
})

#: (from, to) -> (factor, offset): conventions between kinds, allowed only with span=True
SPANS: dict[tuple[str, str], tuple[float, float]] = {
    ("V", "%"): (10.0, 0.0),  # a 0-10 V control voltage shown as 0-100 %
}

#: kind -> (its SI base unit, the exponents of the SI base units), as FMI <UnitDefinitions> want
BASE: dict[str, tuple[str, dict[str, int]]] = {
    "temperature": ("K", {"K": 1}), "temperature difference": ("K", {"K": 1}),
    "mass flow": ("kg/s", {"kg": 1, "s": -1}), "power": ("W", {"kg": 1, "m": 2, "s": -3}),
    "energy": ("J", {"kg": 1, "m": 2, "s": -2}), "fraction": ("1", {}),
    "voltage": ("V", {"kg": 1, "m": 2, "s": -3, "A": -1}), "time": ("s", {"s": 1}),
    "irradiance": ("W/m2", {"kg": 1, "s": -3}), "conductance": ("W/K", {"kg": 1, "m": 2, "s": -3, "K": -1}),
    "heat capacity": ("J/K", {"kg": 1, "m": 2, "s": -2, "K": -1}), "length": ("m", {"m": 1}),
    "volume": ("m3", {"m": 3}), "pressure": ("Pa", {"kg": 1, "m": -1, "s": -2}),
    "mass": ("kg", {"kg": 1}),
}

#: units the code itself holds values in (a device or column unit among these is kept as is)
CODE_UNITS = ("degC", "K", "kg/s", "W", "J", "1", "V", "s", "h", "W/m2", "W/K", "J/K", "m", "m3", "Pa", "kg")


def unit(name: str, where: str = "") -> Unit:
    """The table entry of `name`; ConfigError naming the closest valid units otherwise."""
    try:
        return UNITS[name]
    except (KeyError, TypeError):
        close = closest(name, [u for u in UNITS if u])
        raise ConfigError(f"{where + ': ' if where else ''}unit {name!r} unknown; "
                          + (f"closest: {', '.join(close)}" if close else
                             f"known: {', '.join(sorted(u for u in UNITS if u))}")) from None


def kind(name: str) -> str:
    """The kind of a unit (temperature, mass flow, power, ...)."""
    return unit(name).kind


def si_unit(name: str) -> str:
    """The unit the code holds a quantity given in `name` in (`kW` -> `W`, `°C` -> `degC`)."""
    return name if name in CODE_UNITS else SI[unit(name).kind]


def convertible(from_unit: str, to_unit: str) -> bool:
    """True when both units are known and of the same kind."""
    a, b = UNITS.get(from_unit), UNITS.get(to_unit)
    return a is not None and b is not None and a.kind == b.kind


@cache
def factors(from_unit: str, to_unit: str, difference: bool = False, span: bool = False,
            where: str = "") -> tuple[float, float]:
    """(a, b) with value_in_to_unit = a * value_in_from_unit + b.

    Computed in exact fractions, so e.g. kg/s -> l/min is exactly 60 and degC -> K exactly +273.15.
    ConfigError for an unknown unit (closest names) or kinds that do not match (both kinds).
    """
    if from_unit == to_unit:
        return 1.0, 0.0
    if span and (from_unit, to_unit) in SPANS:
        return SPANS[from_unit, to_unit]
    if span and (to_unit, from_unit) in SPANS:
        f, o = SPANS[to_unit, from_unit]
        return 1.0 / f, -o / f
    u, t = unit(from_unit, where), unit(to_unit, where)
    if u.kind != t.kind:
        raise ConfigError(f"{where + ': ' if where else ''}cannot convert {from_unit!r} ({u.kind}) to "
                          f"{to_unit!r} ({t.kind}); units of the kind {t.kind}: "
                          + ", ".join(n for n, x in UNITS.items() if x.kind == t.kind and n))
    (fu, ou), (ft, ot) = _EXACT[from_unit], _EXACT[to_unit]
    a = fu / ft
    b = Fraction(0) if difference else (ou - ot) / ft
    return float(a), float(b)


def convert(value, from_unit: str, to_unit: str, *, difference: bool = False, span: bool = False,
            where: str = ""):
    """`value` (a number or a numpy array) in `from_unit` expressed in `to_unit`."""
    a, b = factors(from_unit, to_unit, difference, span, where)
    if a == 1.0 and b == 0.0:
        return value
    return value * a + b


__all__ = ["Unit", "UNITS", "SI", "BASE", "SPANS", "CODE_UNITS", "unit", "kind", "si_unit", "convertible",
           "factors", "convert"]
