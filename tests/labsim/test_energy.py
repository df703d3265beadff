"""labsim conserves energy: a day of the whole plant closes its ledger, and the storage scheme
(upwind advection in flux form, conduction, buoyancy by convective adjustment) alone conserves it."""
import numpy as np

from labsim.house import LabHouse
from labsim.storage import CP, Tank, coil_heat


def test_a_labsim_day_closes_its_energy_ledger():
    h = LabHouse("2021-01-10", {"idle_flow_k": 0.7, "valve_leak": 0.1})
    for _ in range(8640):  # one day of 10 s steps
        h.step()
    L = h.closure()
    assert L["fuel"] > 50.0 and L["heat_building"] > 50.0 and L["heat_dhw"] > 3.0
    uses = (L["electricity"] + L["generator_losses"] + L["heat_building"] + L["heat_dhw"]
            + L["losses_tanks"] + L["delta_stored"])
    assert abs(L["fuel"] - uses) < 1e-3 * L["fuel"]
    # the water side (not a remainder): generator heat = building + DHW + tank losses + change of storage
    assert abs(L["water_side_closure"]) < 1e-3
    assert h.chp.starts >= 1 and h.boiler.starts >= 1


def test_the_storage_scheme_conserves_energy():
    rng = np.random.default_rng(3)
    tank = Tank(0.8, 1.63, 50, UA_loss=0.0, T_env=18.0, T_bottom=35.0, T_top=75.0)
    E0 = tank.energy()
    top, bottom = tank.layer(1.55), tank.layer(0.08)
    w_top, w_bot = tank.spread(1.55, 8, True), tank.spread(0.08, 1, False)
    fed = 0.0
    for k in range(3000):
        q = rng.uniform(-0.4, 0.4)
        T_in = rng.uniform(20.0, 85.0)
        if q >= 0:
            (T_out,) = tank.step(10.0, [(w_top, q, T_in)], [(bottom, q)])
        else:
            (T_out,) = tank.step(10.0, [(w_bot, -q, T_in)], [(top, -q)])
        fed += 10.0 * abs(q) * CP * (T_in - T_out)
    assert abs(tank.energy() - E0 - fed) < 1e-9 * E0
    assert np.all(np.diff(tank.T) >= -1e-12)  # buoyancy leaves no inversion


def test_buoyancy_mixes_an_inversion_and_keeps_its_heat():
    tank = Tank(0.5, 1.51, 30, 0.0, 18.0, 40.0, 60.0)
    tank.T[:5] = 80.0  # hot water at the bottom
    E0 = tank.energy()
    tank.step(10.0, [], [])
    assert np.all(np.diff(tank.T) >= -1e-12)
    assert abs(tank.energy() - E0) < 1e-9 * E0


def test_a_coil_gives_what_its_fluid_loses():
    T = np.linspace(20.0, 60.0, 30)
    q, T_out = coil_heat(T, range(15, 24), 640.0, 0.333, 70.0)
    assert abs(q.sum() - 0.333 * CP * (70.0 - T_out)) < 1e-6
    assert T_out < 70.0 and np.all(q >= 0)
