"""The truth of house 1: `plant/houses/house1_truth.toml` (a variant of house 1 on a
pressure-driven header) built by the same compiler as the twin, with the knobs the test
recordings turn.

    from plant.truth import load_truth
    truth = load_truth(start="2021-01-10", network={"k_chp": 12000.0}, storage_layers=80,
                       inlet_mixing_layers=2, sensor_lag={10: 120.0})
    truth.step(60.0); truth.get("chp.T_sup"); truth.get("switch.m_flow_forced"); truth.ledger()

It is a House (plant/house.py) like any other; the signals the twin does not have are the
pressure-driven switch's (switch.p_supply, switch.m_flow_forced, switch.residual). Not for
controllers under test: it exists to generate lab-like recordings whose physics differs from
the twin in known, documented ways (plant/truth/recording.py). The diagnosis is validated against
an independent simulator as well (see docs/diagnose.md).
"""
from __future__ import annotations

from ..housefile import HOUSES
from ..errors import ConfigError
from ..house import House, load_house

TRUTH = HOUSES / "house1_truth.toml"


def load_truth(name_or_path=TRUTH, start: str | None = None, controller: str = "rule_based",
               overrides: dict | None = None, network: dict | None = None, storage_layers: int = 80,
               inlet_mixing_layers: int = 2, sensor_lag: dict | None = None) -> House:
    """The truth house with its knobs as overrides of its file.

    network: NetworkParams fields (plant/hydraulics/pressure_driven.py), {"enabled": False} =
    the ideal switch; storage_layers: heating-storage layers; inflows spread evenly over
    inlet_mixing_layers layers from the port; sensor_lag: {storage sensor 1..10: tau [s]};
    overrides: as in load_house (e.g. {"storage.UA_loss": 40.0}).
    """
    if name_or_path == "house1":
        name_or_path = TRUTH
    n = int(storage_layers)
    if not 1 <= int(inlet_mixing_layers) <= n // 2:
        raise ConfigError(f"inlet_mixing_layers = {inlet_mixing_layers}: allowed 1 … {n // 2}")
    ov = {"storage.n_layers": n}
    volume = (overrides or {}).get("storage.volume", 0.8)
    ov["switch.storage_inlet_mixing"] = (int(inlet_mixing_layers) - 1) * (volume / n)
    for key, value in (network or {}).items():
        ov[f"switch.network.{key}"] = value
    for sensor, tau in (sensor_lag or {}).items():
        if not 1 <= int(sensor) <= 10 or not tau >= 0:
            raise ConfigError(f"sensor_lag {{{sensor}: {tau}}}: sensor 1 … 10, tau >= 0 s")
        ov[f"storage.sensor_lag.{int(sensor)}"] = float(tau)
    ov.update(overrides or {})
    return load_house(name_or_path, start=start, controller=controller, overrides=ov)
