"""Electric heating rod in one layer of a storage, with its own thermostat (house SF4's 6 kW rod,
reference §12.5).

Physics in words
----------------
A resistive rod turns its electric power into heat in the water of the one storage layer it sits
in (link `height`): Q_flow = P, no losses of its own, no heat capacity. The heat is added after
the storage's own step as an explicit, energy-exact update of that layer,
    T[layer] += Q_flow h / (RHO V/N CP),
so the storage kernel is unchanged; a layer left warmer than the one above it is merged by the
kernel's buoyancy at the next step (plant/components/storage.py). The kind's role (`heater`)
makes it emit after the storages, so its line in the `storages` phase follows the storage step.

Thermostat (§12.5: "internal hysteresis 5 K below T_max = 90 °C"): a contact on the start-of-step
layer temperature opens at T >= T_max and closes again below T_max - dT_hysteresis; in between it
holds. It starts closed.

Commands (SG-ready-like; the kind's inputs):
  `<name>.on`     0/1, the relay (SG-ready "release"): 0 = blocked, 1 = released.
  `<name>.P_set`  W, the power the rod may take when released: the PV-surplus mode's limit. The
                  kind writes P_set = P_nom unless it is driven from outside or by a controller,
                  so a plain relay gives full power; a PV-surplus controller drives P_set with
                  the surplus and the rod takes min(P_set, P_nom), clipped at 0.
With `n_stages` > 0 the rod switches in n equal stages (a 3 x 2 kW rod) and takes the largest
number of whole stages not above P_set (never more than the surplus); 0 = continuous (a
thyristor or PWM rod controller). Effective power P = that power while released and the
thermostat is closed, else 0.

Ledger: el -= P h (consumed), heat += P h; nothing is lost (generator_losses 0).

Signals: inputs `on`, `P_set`; outputs `P_el` (W, - consumed), `Q_flow` (W, heat into the layer),
`on_effective` (1 while heating), `thermostat` (1 = contact closed), `E_el` (J, - consumed).

Parameters
----------
| name | unit | meaning |
|---|---|---|
| P_nom | W | rated power (SF4: 6000 W) |
| T_max | degC | thermostat opens at this layer temperature (90 °C) |
| dT_hysteresis | K | it closes again this far below T_max (5 K) |
| n_stages | 1 | 0: continuous power; n: n equal stages of P_nom/n |

Links: `storage` (a native `storage`, not a storage FMU: the update writes its layers), `height`
(m above the storage bottom; SF4: layer 6 of 10 of the 0.86 m3 "BSH1000").

Assumptions: the rod heats one layer only (a real rod spans ~10-20 cm; at 40 layers of a 1.6 m
tank that is one or two layers); no rod temperature or heat-up delay; the thermostat senses the
layer it heats. Tests: tests/plant/test_electric_heater.py (hysteresis, P_set limit and stages,
energy balance in a house to round-off, bad links).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import REQUIRED, Height, Instance, Kind as ComponentKind, indices, link, pack, param
from ..water import CP, RHO


@dataclass(frozen=True)
class Params:
    P_nom: float = param(6000.0, "W", "rated electric power = heat power", 0.0, 1e6)
    T_max: float = param(90.0, "degC", "the thermostat opens at this layer temperature", 20.0, 99.0)
    dT_hysteresis: float = param(5.0, "K", "the thermostat closes again this far below T_max", 0.1, 50.0)
    n_stages: int = param(0, "1", "0: continuous power; n: n equal stages of P_nom/n", 0, 10)


STATES = ("thermostat", "E_el")
# positions in the packed parameters and the state vector, from the declarations
PAR = indices(Params)
X = indices(STATES)
C_LAYER = len(PAR)  # appended by the kind after the packed Params: heat capacity of its layer [J/K]
LAYER = C_LAYER + 1  # ... and then the layer the rod is in (a parameter, not a constant of the
# generated step: a storage re-layered by a diagnosis's scheme is the same compiled plant)


def initial_state(params) -> np.ndarray:
    """The thermostat contact starts closed; no energy yet."""
    return np.array([1.0, 0.0])


@njit(cache=True)
def power(x, p, on, P_set, T_layer):
    """The thermostat on the layer temperature, then the power the rod takes this step [W]."""
    if T_layer >= p[PAR.T_max]:
        x[X.thermostat] = 0.0
    elif T_layer < p[PAR.T_max] - p[PAR.dT_hysteresis]:
        x[X.thermostat] = 1.0
    if on <= 0.5 or x[X.thermostat] < 0.5:
        return 0.0
    P = min(max(P_set, 0.0), p[PAR.P_nom])
    n = p[PAR.n_stages]
    if n > 0.0:
        stage = p[PAR.P_nom] / n
        P = math.floor(P / stage * (1.0 + 1e-12)) * stage  # a surplus of exactly k stages gives k
        P = min(P, p[PAR.P_nom])
    return P


class Kind(ComponentKind):
    """The rod in one layer of a storage; emits itself after the storages."""

    name = "electric_heater"
    Params = Params
    role = "heater"
    LINKS = {"storage": link(REQUIRED, "the storage the rod is in (a native storage)", type=Instance,
                             range=("storage",)),
             "height": link(REQUIRED, "height of the rod above the storage bottom [m]", type=Height)}

    def initial_state(self, inst):
        return initial_state(inst.params)

    def emit(self, c, inst):
        st = c.instances[inst.options["storage"]]
        if st.kind != "storage":
            c.problems.append(f"{inst.at('storage')} = {st.name!r}: a {st.kind}; the rod heats the "
                              "layers of a native storage (kind = \"storage\")")
            return
        layer = c.port_layer(inst, "height", st.name)
        C = RHO * st.params.volume / st.params.n_layers * CP
        x = c.state(inst, self.initial_state(inst))
        p = c.param(inst, np.append(pack(inst.params), [C, float(layer)]))
        on = c.signal(inst, "on", "1", "input", "relay: 1 = released (SG-ready), 0 = blocked")
        P_set = c.signal(inst, "P_set", "W", "input", "power limit when released (PV-surplus mode); "
                                                      "P_nom unless driven from outside")
        c.write_command("control", f"{inst.name}.P_set", f"{p}[{PAR.P_nom}]")
        mod = c.module(__name__)
        P, T = c.var("P_rod"), c.state_of(inst, st)  # the storage's layer temperatures
        k = f"int({p}[{LAYER}])"
        c.emit("hydraulics", f"{P} = {mod}.power({x}, {p}, {on}, {P_set}, {T}[{k}])")
        c.emit("storages", f"{T}[{k}] += {P} * h / {p}[{C_LAYER}]")
        sig = lambda local, unit, desc: c.signal(inst, local, unit, "output", desc)  # noqa: E731
        c.emit("signals",
               f"{x}[{X.E_el}] -= {P} * h",
               f"{sig('P_el', 'W', 'electric power (- consumed)')} = -{P}",
               f"{sig('Q_flow', 'W', 'heat into the storage layer')} = {P}",
               f"{sig('on_effective', '1', '1 while the rod heats')} = 1.0 if {P} > 0.0 else 0.0",
               f"{sig('thermostat', '1', 'thermostat contact: 1 closed, 0 open (layer above T_max)')} = {x}[{X.thermostat}]",
               f"{sig('E_el', 'J', 'electric energy since the start (- consumed)')} = {x}[{X.E_el}]",
               f"{c.ledger_entry(inst, 'el')} -= {P} * h",
               f"{c.ledger_entry(inst, 'heat')} += {P} * h")
