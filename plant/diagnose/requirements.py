"""What a recording must hold to be replayed and compared: the commands replayed into the twin
(and the measured signals that may stand in for them), the boundary conditions taken from the
twin's profiles when absent, and the measured outputs a diagnosis compares."""
from __future__ import annotations

import numpy as np

from ..catalogue import CATALOGUE
from ..errors import ConfigError
from . import cut as cut_mod

COMMANDS = ("chp.on", "chp.y_set", "boiler.U_set", "dhw_pump.on", "mixer.T_sup_set", "mixer.m_flow_set")
# a command the recording may replace by a measured signal (with a warning)
SUBSTITUTES = {"mixer.m_flow_set": "mixer.m_flow", "mixer.T_sup_set": "mixer.T_sup",
               "chp.y_set": "chp.on"}
BOUNDARY = ("weather.T_air", "weather.E_dir", "weather.E_dif", "occupancy.presence", "household.P_el",
            "dhw.m_flow_demand")
NOT_COMPARED_UNITS = ("J", "h", "1", "V", "W/m2")


def comparable() -> list[str]:
    """Measured plant outputs a recording can be compared on (temperatures, flows, powers)."""
    out = []
    for s in CATALOGUE:
        if s.causality != "output" or s.name in BOUNDARY or s.unit in NOT_COMPARED_UNITS:
            continue
        if s.name in ("storage.E_stored", "zone.T_set", "zone.Q_flow_gains", "zone.Q_flow_solar",
                      "dhw.Q_flow_missing", "storage.m_flow"):
            continue
        out.append(s.name)
    return out


#: the house the diagnosis knows: its commands, modes, cuts and effects are written for it
KNOWN_HOUSE = "house1"


def check_house(house) -> None:
    """Refuse a house the diagnosis cannot replay, before anything is read against house 1's
    signals. It replays any house file that declares house 1's diagnosed instances under the
    same names and kinds (house 1 with other parameters, sizes or sensors); the diagnosis of
    other plants (roles declared by the kinds, cuts derived per house) is issue #28."""
    from ..house import load_spec

    spec = load_spec(house)
    where = getattr(spec, "path", house)
    if not hasattr(spec, "instances"):
        raise ConfigError(f"{where}: the diagnosis replays native houses only; this house's plant is an "
                          "FMU ([house] topology = \"fmu\"): diagnose the native house it was exported from")
    known = load_spec(KNOWN_HOUSE).instances
    used = {n.split(".", 1)[0] for n in (*COMMANDS, *BOUNDARY, *comparable())} & set(known)
    missing = sorted(f"{n} ({known[n].kind})" for n in used
                     if n not in spec.instances or spec.instances[n].kind != known[n].kind)
    if missing:
        raise ConfigError(
            f"{where}: the diagnosis knows {KNOWN_HOUSE}'s plant only and this house lacks its "
            f"diagnosed instance(s) {', '.join(missing)} (name and kind); diagnose a recording of "
            f"{KNOWN_HOUSE} or of a house file that keeps those instances (`twin diagnose "
            f"--requirements {KNOWN_HOUSE}` lists what a recording needs)")


def requirements() -> dict:
    return {
        "commands (required; replayed into the twin)": list(COMMANDS),
        "accepted substitutes (with a warning)": {k: v for k, v in SUBSTITUTES.items()},
        "boundary conditions (optional; taken from the twin's profiles by date, checked if present)": list(BOUNDARY),
        "start date (required in [recording] start of the mapping, meta.json, or --start)": ["start"],
        "measured signals (compared; at least one required)": comparable(),
        "measured boundaries (optional; what each signal enables)": [
            f"{sig} -> {what}" for sig, what in cut_mod.requirements().items()],
    }


def check(rec) -> list[str]:
    """Reject a recording that lacks what replay needs; returns warnings for substitutions."""
    warnings = []
    missing = []
    for c in COMMANDS:
        if rec.has(c):
            continue
        sub = SUBSTITUTES.get(c)
        if sub and rec.has(sub):
            v = rec.data[sub].copy()
            if c == "chp.y_set":
                v = np.where(v > 0.5, 1.0, 0.0)
            rec.data[c] = v
            warnings.append(f"{c}: not recorded; replayed from {sub}" + (" (modulation 1 while on)" if c == "chp.y_set" else ""))
        else:
            missing.append(c)
    measured = [s for s in comparable() if rec.has(s)]
    if missing or not measured:
        lines = []
        if missing:
            lines.append("recording lacks the command(s) replay needs: " + ", ".join(missing))
        if not measured:
            lines.append("recording has no measured signal to compare")
        req = requirements()
        lines.append("a recording for replay must contain:")
        for k, v in req.items():
            lines.append(f"  {k}: {', '.join(v) if isinstance(v, list) else v}")
        raise ConfigError("\n".join(lines))
    return warnings
