"""Synthetic lab-like recordings from the twin with a KNOWN injected effect (tests, benchmark).

    rec = synth.make("idle_generator_flow", 0.25, days=3)   # -> recording_io.Samples
    synth.write("storage_mixing", 2000.0, "case.csv", "columns.toml", days=7)

The 'truth' is the twin with its rule-based controller and the effect injected (a house-file
override, or a post-processing of one recorded sensor), sampled every `interval` seconds, with
sensor noise and quantisation. The commands are recorded as they were, so replay sees the same
generator set-points. CASES lists the public suite: effect -> (injection, default size).
"""
from __future__ import annotations

import numpy as np

from ..catalogue import CATALOGUE
from ..diagnose.effects.sensor import first_order
from ..diagnose.recording_io import Samples, write_csv
from ..diagnose.requirements import BOUNDARY
from ..diagnose.roles import of as roles_of

# a lab-like sensor set (the CoSES lab measures these; chp.m_flow is concealed by default)
LAB_SIGNALS = (
    ["chp.T_sup", "chp.T_ret", "chp.Q_flow", "chp.P_el",
     "boiler.T_sup", "boiler.T_ret", "boiler.m_flow", "boiler.Q_flow",
     "mixer.T_sup", "mixer.T_ret", "mixer.m_flow",
     "switch.T_sup", "switch.T_ret", "zone.T_room", "dhw_pump.m_flow"]
    + [f"storage.T_sensor_{i}" for i in range(1, 11)]
    + [f"dhw_storage.T_sensor_{i}" for i in (2, 5, 8, 10)]
)
NOISE = {"degC": (0.05, 0.1), "kg/s": (0.001, 0.0), "W": (20.0, 0.0)}  # sigma, quantisation step

# effect -> (kind, key or signal, default size)
CASES = {
    "none": ("override", None, 0.0),
    "idle_generator_flow": ("override", "switch.idle_flow.chp", 0.25),
    "pump_coupling": ("override", "switch.pump_coupling.chp", 0.3),
    "heat_loss": ("override", "storage.UA_loss", 80.0),
    "storage_mixing": ("override", "switch.storage_inlet_mixing", 0.1),
    "thermal_mass": ("override", "chp.V_water", 0.02),
    "sensor_lag": ("lag", "storage.T_sensor_10", 600.0),
    "sensor_offset": ("offset", "switch.T_ret", 1.5),
    "transport_delay": ("delay", "mixer.T_ret", 300.0),
    "valve_leakage": ("override", "mixer.leak", 0.1),
}


def make(effect: str = "none", size: float | None = None, days: float = 3.0, start: str = "2021-01-10",
         interval: float = 60.0, seed: int = 1, signals=None, noise: bool = True,
         conceal=("chp.m_flow",), base: dict | None = None) -> Samples:
    """base: house-file overrides of the operating conditions (e.g. a low heating set-point, so
    that the mixing valve closes), applied with and without the effect alike."""
    kind, key, default = CASES[effect]
    size = default if size is None else size
    from ..house import load_house

    overrides = dict(base or {})
    if kind == "override" and key:
        overrides[key] = size
    house = load_house("house1", start=start, overrides=overrides or None)
    times, rows = house.run(days * 86400.0, dt=1.0, out_interval=interval)
    col = {n: i for i, n in enumerate(CATALOGUE.names)}
    signals = [s for s in (signals or LAB_SIGNALS) if s not in conceal]
    data = {c: rows[:, col[c]].copy() for c in roles_of("house1").commands}
    for b in BOUNDARY[:1]:
        data[b] = rows[:, col[b]].copy()
    rng = np.random.default_rng(seed)
    for s in signals:
        v = rows[:, col[s]].copy()
        if kind == "lag" and s == key:  # the continuous lag of the signal between its samples
            v = first_order(times, v, size)
        elif kind == "offset" and s == key:
            v = v + size
        elif kind == "delay" and s == key:
            k = int(round(size / interval))
            v = np.concatenate([np.full(k, v[0]), v[:-k]]) if k else v
        if noise:
            sigma, q = NOISE.get(CATALOGUE.signal(s).unit, (0.0, 0.0))
            v = v + rng.normal(0.0, sigma, len(v))
            if q:
                v = np.round(v / q) * q
        data[s] = v
    return Samples(f"synthetic:{effect}={size}", start, times.copy(), data, [],
                   np.ones(len(times), dtype=bool), {})


def write(effect: str, size: float | None, csv_path, mapping_path, **kw) -> Samples:
    rec = make(effect, size, **kw)
    write_csv(csv_path, rec.time, rec.data, mapping_path, start=rec.start)
    return rec
