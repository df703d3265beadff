"""The solar collector's coils checked before the first step (plant/components/solar_collector.py):
each runs downward, two behind a valve need the upper one's conductance and its inlet above the
lower one's, and what only a valve between two coils has (UA_upper, leak) is refused without one.
Each problem names the house file's key at its line and the fix."""
from __future__ import annotations

from ..component import is_number


def check(c, inst, valve) -> None:
    """Each coil runs downward (inlet above outlet); two coils need UA_upper and the upper coil
    above the lower one; UA_upper or a leak without a second coil is a mistake."""
    o = inst.options
    for side in ("upper", "lower") if valve else ("",):
        top, bottom = (f"{k}.{side}" if side else k for k in ("top", "bottom"))
        t, b = (o[k][side] if side and _valve(o[k]) else o[k] for k in ("top", "bottom"))
        # a plain height beside a valve is named top.upper at the table's line, as before
        where = inst.at(top) if side and not _valve(o["top"]) else inst.at("top") + top[3:]
        if is_number(t) and is_number(b) and t < b:
            c.problems.append(f"{where} = {t}: must be above {bottom} = {b}")
    ua_up = inst.params.UA_upper
    if valve and not ua_up > 0.0:
        c.problems.append(f"{inst.at('UA_upper')} = {ua_up}: two coils need the upper coil's conductance "
                          "> 0 W/K (area x 675 W/(m2 K))")
    if not valve and ua_up > 0.0:
        c.problems.append(f"{inst.at('UA_upper')} = {ua_up}: only with two coils, top = {{ upper = ..., "
                          "lower = ... } and bottom = { upper = ..., lower = ... }")
    if not valve and inst.params.leak > 0.0:
        c.problems.append(f"{inst.at('leak')} = {inst.params.leak}: only a solar valve between two coils "
                          "leaks; top = { upper = ..., lower = ... } and bottom = { upper = ..., lower = ... }")
    if valve and isinstance(o["top"], dict) and is_number(o["top"].get("upper")) and is_number(o["top"].get("lower")) \
            and o["top"]["upper"] <= o["top"]["lower"]:
        c.problems.append(f"{inst.at('top')}.upper = {o['top']['upper']}: the upper coil's inlet must be above "
                          f"the lower coil's, top.lower = {o['top']['lower']}")


def _valve(port) -> bool:
    """A port given as a three-way valve's two heights (what `c.port_layers` reads as two)."""
    return isinstance(port, dict) and set(port) == {"upper", "lower"}
