"""What a recording must hold to be replayed and compared: the commands replayed into the twin
(and the measured signals that may stand in for them), the boundary conditions taken from the
twin's profiles when absent, and the measured outputs a diagnosis compares. The commands, their
substitutes and the outputs never compared are the house's roles (roles.py)."""
from __future__ import annotations

import numpy as np

from ..errors import ConfigError
from . import cut as cut_mod
from . import roles as roles_mod

BOUNDARY = ("weather.T_air", "weather.E_dir", "weather.E_dif", "occupancy.presence", "household.P_el",
            "dhw.m_flow_demand")
NOT_COMPARED_UNITS = ("J", "h", "1", "V", "W/m2")


def profile_differs(err: float, scale: float, signal: str) -> bool:
    """Whether a recorded boundary differs from the twin's profile of it: an RMS difference err
    beyond a fifth of the profile's own spread scale (the outdoor air 0.5 K more: a sensor's
    reading of it)."""
    return err > 0.2 * scale + (0.5 if signal == "weather.T_air" else 0.0)


def comparable(house="house1") -> list[str]:
    """Measured plant outputs a recording can be compared on (temperatures, flows, powers)."""
    roles = roles_mod.of(house)
    unmeasured = roles.unmeasured
    return [s.name for s in roles.catalogue if s.causality == "output" and s.name not in BOUNDARY
            and s.unit not in NOT_COMPARED_UNITS and s.name not in unmeasured]


def check_house(house) -> None:
    """Refuse a house the diagnosis cannot replay (an FMU-backed one), before a recording is read."""
    from ..house import load_spec

    spec = load_spec(house)
    if not hasattr(spec, "instances"):
        raise ConfigError(f"{getattr(spec, 'path', house)}: the diagnosis replays native houses only; this house's "
                          "plant is an FMU ([house] topology = \"fmu\"): diagnose the native house it was exported from")


OWN = "commands of a unit's own control (optional; replayed where recorded, else the twin's control decides)"


def requirements(house="house1") -> dict:
    """What a recording of `house` must hold, for any house file: its commands, the measured
    signals per subsystem, and per cut what it must measure to be replayed there."""
    roles = roles_mod.of(house)
    per: dict = {}
    for s in comparable(house):
        per.setdefault(roles.subsystem(s), []).append(s)
    out = {
        "commands (required; replayed into the twin)": list(roles.commands),
        "accepted substitutes (with a warning)": {k: f"or {v}" for k, v in roles.substitutes.items()},
        OWN: list(roles.own_commands),
        "boundary conditions (optional; taken from the twin's profiles by date, checked if present)":
            [b for b in BOUNDARY if b in roles.catalogue],
        "start date (required in [recording] start of the mapping, meta.json, or --start)": ["start"],
        "measured signals per subsystem (compared; at least one required)": per,
        "cuts (what a recording must measure to be replayed without the twin's building and profiles)":
            cut_mod.cuts_needed(house),
        "measured boundaries (optional; what each signal enables)": [
            f"{sig} -> {what}" for sig, what in cut_mod.requirements(house).items()],
    }
    if not out[OWN]:
        del out[OWN]     # a house whose kinds have none: no empty heading
    return out


def lines(req: dict) -> list[str]:
    """requirements() as text, one line per entry."""
    out = []
    for k, v in req.items():
        out.append(f"{k}:")
        items = v.items() if isinstance(v, dict) else [(x, None) for x in v]
        out += [f"  {name}" + (f": {', '.join(sub) if isinstance(sub, list) else sub}" if sub else "")
                for name, sub in items]
    return out


def check(rec, house="house1") -> list[str]:
    """Reject a recording that lacks what replay needs, or holds signals the house does not have
    (a recording of another house); returns warnings for substitutions."""
    roles = roles_mod.of(house)
    alien = [s for s in rec.data if s not in roles.catalogue]
    if alien:
        raise ConfigError(f"{rec.source}: the recording holds signals {house} does not have: "
                          f"{', '.join(alien[:6])}{' ...' if len(alien) > 6 else ''}: a recording of another "
                          f"house? Diagnose it with its own house file (--house), or map its columns onto "
                          f"{house}'s signals (`twin diagnose --requirements {house}`)")
    run = {u.command: u.on_above for u in (*roles.generators, *roles.circuits, *roles.chargers)}
    warnings = []
    missing = []
    for c in roles.commands:
        if rec.has(c):
            continue
        sub = roles.substitutes.get(c)
        if sub and rec.has(sub):
            v = rec.data[sub].copy()
            if sub in run:  # a run command for a modulation: 1 while on
                v = np.where(v > run[sub], 1.0, 0.0)
            rec.data[c] = v
            rec.substituted[c] = sub
            warnings.append(f"{c}: not recorded; replayed from {sub}" + (" (modulation 1 while on)" if sub in run else ""))
        else:
            missing.append(c)
    measured = [s for s in comparable(house) if rec.has(s)]
    if missing or not measured:
        problems = []
        if missing:
            problems.append("recording lacks the command(s) replay needs: " + ", ".join(missing))
        if not measured:
            problems.append("recording has no measured signal to compare")
        problems.append("a recording for replay must contain:")
        problems += ["  " + line for line in lines(requirements(house))]
        raise ConfigError("\n".join(problems))
    return warnings
