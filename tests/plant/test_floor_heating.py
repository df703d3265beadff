"""Floor heating: nominal emission at 40/30/20 degC, the exponent law at part load in steady
state, cooling with no flow, energy balance alone and in a house, bad parameters."""
import math
from dataclasses import replace

import numpy as np
import pytest

from plant.component import build_params, pack
from plant.components import floor_heating as fh
from plant.components.radiator import lmtd
from plant.declaration import HOUSES
from plant.errors import ConfigError
from plant.house import load_house
from plant.water import CP


def steady(P, m, T_sup, T_room, dt=60.0):
    """Run to steady state; returns (T_ret, emission, water-side heat m cp (T_sup - T_ret))."""
    p, x = pack(P), fh.initial_state(P)
    tau = fh.capacity(P) / (m * CP + P.Q_nominal / 14.4)
    for _ in range(int(40 * tau / dt)):
        fh.step(dt, x, p, m, T_sup, T_room)
    T_ret, Q = fh.step(dt, x, p, m, T_sup, T_room)
    return T_ret, Q, m * CP * (T_sup - T_ret)


def test_nominal_emission_at_nominal_temperatures():
    P = fh.Params()
    m = P.Q_nominal / (CP * 10.0)  # the flow of 40/30 at nominal emission
    T_ret, Q, Q_water = steady(P, m, 40.0, 20.0)
    assert T_ret == pytest.approx(30.0, abs=1e-6)  # the dynamics settle on the nominal return
    assert Q == pytest.approx(P.Q_nominal, rel=1e-6)  # within 1 % asked; exact to the settling error
    assert Q_water == pytest.approx(P.Q_nominal, rel=1e-6)


@pytest.mark.parametrize("T_sup, share", [(35.0, 0.6), (30.0, 0.4), (27.0, 0.25)])
def test_part_load_follows_the_exponent_law(T_sup, share):
    """At a lower supply and flow the steady emission is Q_N (LMTD/LMTD_N)^1.1 and what the water
    brings in (m cp dT): measured by the water side, not by the emission formula."""
    P = fh.Params()
    m = share * P.Q_nominal / (CP * 10.0)
    T_ret, Q, Q_water = steady(P, m, T_sup, 20.0)
    law = P.Q_nominal * (lmtd(T_ret - 20.0, T_sup - 20.0) / lmtd(10.0, 20.0)) ** 1.1
    assert Q_water == pytest.approx(law, rel=1e-4)
    assert Q_water < P.Q_nominal
    # the exponent recovered from two steady points (not the linear law of exponent 1)
    T_ret2, _, Q2 = steady(P, m, 40.0, 20.0)
    n = math.log(Q2 / Q_water) / math.log(lmtd(T_ret2 - 20.0, 20.0) / lmtd(T_ret - 20.0, T_sup - 20.0))
    assert n == pytest.approx(1.1, abs=1e-3)


def test_without_flow_the_floor_cools_towards_the_room_and_keeps_energy():
    P = fh.Params()
    p, x = pack(P), np.array([32.0])
    emitted = 0.0
    for _ in range(24 * 60 * 4):  # four days of 60 s
        _, Q = fh.step(60.0, x, p, 0.0, 40.0, 20.0)
        emitted += Q * 60.0
    assert 20.0 < x[0] < 26.0
    assert emitted == pytest.approx(fh.capacity(P) * (32.0 - x[0]), rel=1e-12)


def test_a_trickle_gives_no_more_than_it_brings_in():
    P = fh.Params()
    p = pack(P)
    own = fh.emission(p, 25.0, 40.0, 0.0, 20.0)
    assert fh.emission(p, 25.0, 40.0, 1e-4, 20.0) == pytest.approx(own + 1e-4 * CP * 15.0, rel=1e-12)
    full = fh.emission(p, 25.0, 40.0, 0.2, 20.0)  # a real flow: the LMTD law
    assert full == pytest.approx(P.Q_nominal * (lmtd(5.0, 20.0) / lmtd(10.0, 20.0)) ** 1.1, rel=1e-12)


def test_screed_slows_the_floor_down():
    P = fh.Params()
    light = replace(P, C_screed=0.0)
    m = P.Q_nominal / (CP * 10.0)
    temps = []
    for params in (P, light):
        p, x = pack(params), np.array([20.0])
        for _ in range(3600):
            fh.step(1.0, x, p, m, 40.0, 20.0)
        temps.append(x[0])
    assert temps[0] < 22.0 < 29.0 < temps[1]  # an hour: the screed barely warmed, bare pipes near steady


def test_bad_parameters_are_reported_together():
    with pytest.raises(ConfigError) as exc:
        build_params(fh.Params, {"exponent": 2.0, "C_screed": -1.0, "Q_nominl": 1.0}, "house.toml [floor]")
    msg = str(exc.value)
    assert "[floor] exponent = 2.0: out of range; allowed 1.0 … 1.5 1" in msg
    assert "[floor] C_screed = -1.0: out of range" in msg
    assert "[floor] Q_nominl: unknown parameter; did you mean Q_nominal" in msg


FLOOR_HOUSE = '''
[house]
name = "floor_heating"
base = "{base}"
remove = ["radiator"]

[floor]
kind = "floor_heating"
zone = "zone"
Q_nominal = 9000.0

[mixer]
emitter = "floor"

[thermostat]
T_sup_constant = 40.0
'''


def test_floor_heating_in_a_house_balances_and_heats_the_zone(tmp_path):
    """House 1 with floor heating (40 degC supply) in the radiators' place, two January days."""
    path = tmp_path / "floor.toml"
    path.write_text(FLOOR_HOUSE.format(base=HOUSES / "house1.toml"))
    house = load_house(path, start="2021-01-10")
    E0 = fh.capacity(house.decl.instances["floor"].params) * house.state("floor")[0]
    times, values = house.run(2 * 86400, dt=1.0, out_interval=600)
    L = house.ledger()
    assert L["closure"] < 1e-9
    cat = house.catalogue
    room = values[:, cat.index("zone.T_room")]
    T_sup = values[:, cat.index("mixer.T_sup")]
    assert L["building_floor"] > 0.0
    flowing = values[:, cat.index("mixer.m_flow")] > 0.05
    assert np.all(T_sup[flowing & (times > 3600)] < 41.0)  # the mixer holds the 40 degC supply
    assert abs(room[times > 86400].mean() - 20.0) < 1.5  # the floor keeps the zone near its set-points
    # the floor's own balance: what the circuit brought in = emitted + stored in water and screed
    E1 = fh.capacity(house.decl.instances["floor"].params) * house.state("floor")[0]
    assert L["building_floor"] > 0.5 * abs(E1 - E0)
