"""The PHIL house's live boundaries (plant/components/phil_boundary.py): the hot-water demand's
energy follows the measured cold water, the collector's heat follows the measured return and
flow, and the house's ledger closes with both."""
from __future__ import annotations

from plant.house import load_house


def _house():
    return load_house("house1_phil", controller="rule_based", overrides={"profiles.typeday": 4})


def _run(house, seconds, **inputs):
    for _ in range(int(seconds / 10)):
        house.set("mixer.T_sup", house.get("mixer.T_sup_set"))
        house.set("mixer.m_flow", house.get("mixer.m_flow_set"))
        for name, value in inputs.items():
            house.set(name.replace("__", "."), value)
        house.step(10.0)


def test_dhw_demand_energy_takes_the_measured_cold_water():
    warm, cold = _house(), _house()
    _run(warm, 10 * 3600, dhw__T_cold=20.0)
    _run(cold, 10 * 3600, dhw__T_cold=10.0)
    E_warm, E_cold = warm.get("dhw.E_set"), cold.get("dhw.E_set")
    assert E_cold > 1e6                                   # the morning's draws happened
    # same profile, E = m_draw cp (45 - T_cold) dt: the ratio is (45 - 20) / (45 - 10)
    assert abs(E_warm / E_cold - 25.0 / 35.0) < 1e-9
    L = cold.ledger()
    assert abs(L["heat_dhw"] - E_cold) < 1e-6 * E_cold and L["closure"] < 1e-9


def test_collector_heat_follows_the_measured_return_and_flow():
    house = _house()
    _run(house, 11 * 3600)                                  # no flow: the collector heats up
    assert house.get("solar.Q_flow") == 0.0 and house.get("solar.T_collector") > 40.0
    _run(house, 1800, solar__T_ret=30.0, solar__m_flow=0.1)  # the lab's pump runs
    Q, T_sup = house.get("solar.Q_flow"), house.get("solar.T_sup")
    assert 100.0 < Q < 1.312 * 1000.0                        # below the irradiance on 1.3 m2
    assert abs(Q - 0.1 * 4180.0 * (T_sup - 30.0)) < 1e-6 * Q
    L = house.ledger()
    assert L["fuel_solar"] > 0 and abs(L["residual"]) < 1e-6 * L["fuel"]
