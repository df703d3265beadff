"""The district-heating substation's rules: extract heat from the grid when the storage runs
cold, feed heat in when it runs hot (the lab's CHN_S_FW_HC_set / CHN_S_FW_TG_set, reference §8.1,
§13.1), switched off by default so that a house run alone behaves as without a substation.

Upstream has no built-in substation controller: the SiL exposes only the substation's flows
(§13.1) and the house models' "standard control" covers the generators alone (§12). These rules
are the twin's, and their thresholds are stated assumptions in each house's .md. Two
edge-triggered hysteresis switches, as every built-in controller (§12):

  extraction   on when T_top < T_extract_on, off when T_top > T_extract_off
  feed-in      on when T_upper > T_feed_on, off when T_upper < T_feed_off
               (never while extracting: extraction wins when both would hold)

T_top and T_upper are whichever signals the house links (the storage's top sensor and an upper
sensor). Outputs, in the substation's sign convention (plant/components/substation.py: + extraction,
- feed-in): m_flow_set = +m_flow_extract, -m_flow_feed or 0, and m_flow_grid_set = m_flow_grid
while either runs, else 0. With `active = 0` (the default) both outputs are 0 and the states stay
0: the substation moves nothing. A district switches it on with the override
{"substation_control.active": 1}; an output driven from outside (gateway, bind) is not written.
The states are also the controller's output signals (`<name>.extracting`, `<name>.feeding_in`).

Parameters
----------
| name | unit | meaning |
|---|---|---|
| active | 1 | 0: outputs 0 (a house alone); 1: the rules run |
| T_extract_on, T_extract_off | degC | extraction starts below / stops above (T_top) |
| T_feed_on, T_feed_off | degC | feed-in starts above / stops below (T_upper) |
| m_flow_extract, m_flow_feed | kg/s | house-side flow while extracting / feeding in (magnitudes) |
| m_flow_grid | kg/s | grid-side flow while either runs |
| period, sensor_resolution | s, K | scan period and the sensor resolution the rules see |

Tests: tests/plant/test_substation_rules.py (inactive: house 1 unchanged; active with a 70 degC
grid: a cold house extracts and the ledger closes; a hot storage feeds in; hysteresis).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Kind as ComponentKind, indices, link, param
from .rule_based import quantize

STATES = ("extracting", "feeding_in", "since_scan")


@dataclass(frozen=True)
class Params:
    active: int = param(0, "1", "0: the substation moves nothing (a house alone); 1: the rules run", 0, 1)
    T_extract_on: float = param(55.0, "degC", "extraction starts when T_top is below", 10, 95)
    T_extract_off: float = param(60.0, "degC", "extraction stops when T_top is above", 10, 95)
    T_feed_on: float = param(75.0, "degC", "feed-in starts when T_upper is above", 10, 99)
    T_feed_off: float = param(70.0, "degC", "feed-in stops when T_upper is below", 10, 99)
    m_flow_extract: float = param(0.15, "kg/s", "house-side flow while extracting", 0.0, 100.0)
    m_flow_feed: float = param(0.15, "kg/s", "house-side flow while feeding in", 0.0, 100.0)
    m_flow_grid: float = param(0.20, "kg/s", "grid-side flow while extracting or feeding in", 0.0, 100.0)
    period: float = param(1.0, "s", "scan period: the rules are evaluated this often", 0.0, 3600.0)
    sensor_resolution: float = param(0.0, "K", "sensor resolution the rules see (0: exact)", 0.0, 5.0)


# positions in the packed parameters and the state vector, from the declarations
P = indices(Params)
X = indices(STATES)


def initial_state(params: Params) -> np.ndarray:
    x = np.zeros(len(STATES), dtype=np.float64)
    x[X.since_scan] = 1e300  # the first step scans
    return x


@njit(cache=True)
def step(dt, x, p, T_top, T_upper):
    """Scan when a period has passed; returns (m_flow_set, m_flow_grid_set)."""
    if p[P.active] < 0.5:
        return 0.0, 0.0
    x[X.since_scan] += dt
    if x[X.since_scan] + 1e-9 >= p[P.period]:
        x[X.since_scan] = 0.0
        r = p[P.sensor_resolution]
        T_top, T_upper = quantize(T_top, r), quantize(T_upper, r)
        if T_top > p[P.T_extract_off]:
            x[X.extracting] = 0.0
        elif T_top < p[P.T_extract_on]:
            x[X.extracting] = 1.0
        if T_upper < p[P.T_feed_off] or x[X.extracting] > 0.5:
            x[X.feeding_in] = 0.0
        elif T_upper > p[P.T_feed_on]:
            x[X.feeding_in] = 1.0
    if x[X.extracting] > 0.5:
        return p[P.m_flow_extract], p[P.m_flow_grid]
    if x[X.feeding_in] > 0.5:
        return -p[P.m_flow_feed], p[P.m_flow_grid]
    return 0.0, 0.0


class Kind(ComponentKind):
    """Storage temperatures in (signal links), the substation's house- and grid-side flows out."""

    name = "substation_rules"
    Params = Params
    role = "controller"
    INPUTS = ("T_top", "T_upper")
    OUTPUTS = ("m_flow_set", "m_flow_grid_set")
    LINKS = {"inputs": link(REQUIRED, "measurements: T_top (extraction), T_upper (feed-in) = signal names",
                            type=dict),
             "outputs": link(REQUIRED, "commands: m_flow_set, m_flow_grid_set = the substation's input signals",
                             type=dict)}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        from . import check_keys, emit_step

        check_keys(c, inst, self.INPUTS, self.OUTPUTS)
        for key in self.OUTPUTS:
            if key not in inst.options["outputs"]:
                c.problems.append(f"{inst.at('outputs')}.{key}: missing; link it to the substation's input, "
                                  f"e.g. {key} = \"substation.{key}\"")
        q = inst.params
        if q.T_extract_on > q.T_extract_off:
            c.problems.append(f"{inst.at('T_extract_on')} = {q.T_extract_on:g}: above T_extract_off = "
                              f"{q.T_extract_off:g}; extraction must start below where it stops")
        if q.T_feed_off > q.T_feed_on:
            c.problems.append(f"{inst.at('T_feed_off')} = {q.T_feed_off:g}: above T_feed_on = "
                              f"{q.T_feed_on:g}; feed-in must stop below where it starts")
        x = emit_step(c, self, inst, __name__)
        sig = lambda local, desc: c.signal(inst, local, "1", "output", desc)  # noqa: E731
        c.emit("signals",
               f"{sig('extracting', 'extraction command of the rules (0/1)')} = {x}[{X.extracting}]",
               f"{sig('feeding_in', 'feed-in command of the rules (0/1)')} = {x}[{X.feeding_in}]")
