"""TruthHouse: house 1 on the pressure-driven network (a stand-in for the lab plant).

    from plant.truth import load_truth
    truth = load_truth("house1", start="2021-01-10", network={"k_chp": 12000.0},
                       storage_layers=80, inlet_mixing_layers=2, sensor_lag={10: 120.0})
    truth.step(60.0); truth.get("chp.T_sup"); truth.aux("chp.m_flow_forced"); truth.ledger()

Same public API as plant.house.House (get/set/release/step/run/ledger/snapshot/restore; the
signal catalogue is the twin's), plus `aux(name)` for quantities the twin does not have
(`AUX_NAMES` in plant/truth/solver.py: the flow the network forces through the CHP,
link/CHP-line/storage flows, node pressures, pump speeds, ...).
Not for controllers under test: it exists to generate lab-like recordings whose physics differs
from the twin in known, documented ways (plant/truth/recording.py).
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np

from .. import housefile
from ..component import build_params
from ..components import pipe
from ..errors import ConfigError
from ..house import House
from ..water import CP, RHO
from . import hydraulic_network as net
from . import solver as tsolver


def load_truth(name_or_path="house1", start: str | None = None, controller: str = "rule_based",
               overrides: dict | None = None, network: dict | None = None, storage_layers: int = 80,
               inlet_mixing_layers: int = 2, sensor_lag: dict | None = None) -> "TruthHouse":
    """Assemble the truth of a house file.

    overrides: house-file overrides as in load_house (e.g. {"storage.UA_loss": 40.0});
    network: NetworkParams fields (plant/truth/hydraulic_network.py), {"enabled": False} = ideal
    switch; storage_layers: heating-storage layers (80 default; inflows spread over
    inlet_mixing_layers layers from the port); sensor_lag: {storage sensor number 1..10: tau [s]}.
    """
    ov = dict(overrides or {})
    ov.setdefault("storage.n_layers", int(storage_layers))
    spec = housefile.load(name_or_path, ov)
    net_params = build_params(net.NetworkParams, dict(network or {}), "[network]")
    n_layers = spec.params["storage"].n_layers
    if not 1 <= int(inlet_mixing_layers) <= n_layers // 2:
        raise ConfigError(f"inlet_mixing_layers = {inlet_mixing_layers}: allowed 1 … {n_layers // 2}")
    lags = np.zeros(10)
    for sensor, tau in (sensor_lag or {}).items():
        if not 1 <= int(sensor) <= 10 or not tau >= 0:
            raise ConfigError(f"sensor_lag {{{sensor}: {tau}}}: sensor 1 … 10, tau >= 0 s")
        lags[int(sensor) - 1] = float(tau)
    return TruthHouse(spec, start=start, controller=controller, net_params=net_params,
                      inlet_mixing_layers=int(inlet_mixing_layers), sensor_lag=lags)


class TruthHouse(House):
    def __init__(self, spec, start=None, controller="rule_based", net_params=None,
                 inlet_mixing_layers: int = 1, sensor_lag=None):
        self.net_params = net_params or net.NetworkParams()
        self.inlet_mixing_layers = inlet_mixing_layers
        self.sensor_lag = np.zeros(10) if sensor_lag is None else np.asarray(sensor_lag, dtype=float)
        self._pipe_j = pipe.Params(V=0.005, T_init=spec.params["return_header"].T_init)
        self._ready = False
        super().__init__(spec, start=start, controller=controller)

    def _extend(self):
        """Add the truth's states, parameters and scratch arrays to what House assembled."""
        x_tr = np.zeros(tsolver.N_XT)
        x_tr[tsolver.XT_LAG0:tsolver.XT_LAG0 + 10] = np.nan
        x_j = pipe.initial_state(self._pipe_j)
        self._x0 = tuple(self._x0[:11]) + (x_tr, x_j, np.zeros_like(self._x0[0]))
        p_tr = np.zeros(tsolver.N_PT)
        p_tr[tsolver.PT_NMIX] = self.inlet_mixing_layers
        p_tr[tsolver.PT_LAG0:tsolver.PT_LAG0 + 10] = self.sensor_lag
        from ..component import pack

        self._p = tuple(self._p[:13]) + (net.pack(self.net_params), p_tr, pack(self._pipe_j))
        n = self.inlet_mixing_layers
        p0, p1, p2 = self._ports[:3]
        self._ports = ((np.zeros(n, dtype=np.int64), p0[1]),
                       (np.zeros(n), np.zeros(n)) + tuple(p1[2:]),
                       p2,
                       (np.zeros(net.N_SOL),))
        self._ready = True

    def reset(self) -> None:
        if not self._ready:
            self._extend()
        super().reset()

    def _advance(self, dt, n, out=None, rec_every=0):
        h = dt / n
        out = out if out is not None else np.zeros((0, len(self.catalogue) + 1))
        rows = tsolver.run(n, h, self.t, self._x, self._p, self._tabs, self._prof, self._ports,
                           self._s, self._remote, self._ledger, out, rec_every)
        self.t += dt
        return rows

    def aux(self, name: str) -> float:
        """A truth-only quantity (see plant.truth.solver.AUX_NAMES)."""
        if name not in tsolver.AUX_NAMES:
            raise ConfigError(f"aux {name!r}: unknown; known: {', '.join(sorted(tsolver.AUX_NAMES))}")
        return float(self._x[11][tsolver.AUX_NAMES[name]])

    def stored_energy(self) -> float:
        E = super().stored_energy()
        if len(self._x) > 12:
            E += CP * RHO * self._pipe_j.V * float(self._x[12][0])
        return E
