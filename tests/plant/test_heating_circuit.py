"""Zone, radiators, mixing station and thermostat: nominal points, steady states, limits, energy."""
import numpy as np
import pytest

from plant.component import pack
from plant.components import mixing_station, pipe, radiator, zone
from plant.controllers import room_thermostat
from plant.water import CP, RHO


def test_radiator_emits_nominal_power_at_nominal_temperatures():
    P = radiator.Params()
    p, x = pack(P), np.array([45.0])
    m = P.Q_nominal / (CP * 15.0)  # the flow that gives 60/45 at nominal emission
    T_out, Q = radiator.step(1.0, x, p, m, 60.0, 21.0)
    assert Q == pytest.approx(8778.0, rel=1e-6)
    assert x[0] == pytest.approx(45.0, abs=1e-6)  # steady: return stays at 45 degC


def test_radiator_without_flow_cools_towards_the_room_and_keeps_energy():
    P = radiator.Params()
    p, x = pack(P), np.array([50.0])
    C = CP * RHO * P.V_water
    emitted = 0.0
    for _ in range(3600 * 6):
        _, Q = radiator.step(1.0, x, p, 0.0, 60.0, 20.0)
        emitted += Q
    assert 20.0 < x[0] < 30.0
    assert emitted == pytest.approx(C * (50.0 - x[0]), rel=1e-9)


def test_zone_steady_state_is_gains_over_conductance():
    P = zone.Params()
    p, x = pack(P), zone.initial_state(P)
    Q_heat = 5000.0
    for _ in range(60 * 24 * 60):  # 60 days of 60 s: the envelope's time constant is ~5 days
        zone.step(60.0, x, p, 0.0, 0.0, 0.0, 0.0, 0.0, Q_heat)
    H = P.H_direct + 1.0 / (1.0 / P.H_mass + 1.0 / P.H_envelope)
    assert x[0] == pytest.approx(Q_heat / H, abs=0.05)


def test_zone_setpoint_has_night_reduction():
    p = pack(zone.Params())
    assert zone.setpoint(p, 12 * 3600.0) == 21.0
    assert zone.setpoint(p, 23.5 * 3600.0) == 18.0
    assert zone.setpoint(p, 86400 + 6.5 * 3600.0) == 18.0
    assert zone.setpoint(p, 86400 + 7.5 * 3600.0) == 21.0


def test_mixing_station_reaches_set_supply_temperature_at_actuator_speed():
    P = mixing_station.Params()
    p, x = pack(P), mixing_station.initial_state(P)
    _, _, T, y = mixing_station.step(1.0, x, p, 55.0, 0.2, 75.0, 35.0)
    ys = []
    for _ in range(600):
        m, m_prim, T, y = mixing_station.step(1.0, x, p, 55.0, 0.2, 75.0, 35.0)
        ys.append(y)
    assert T == pytest.approx(55.0, abs=0.2)
    assert m == pytest.approx(0.2) and m_prim == pytest.approx(0.2 * y)
    assert max(np.diff(ys)) <= 1.0 / P.t_stroke + 1e-12  # finite actuator speed
    m, _, _, _ = mixing_station.step(1.0, x, p, 55.0, 5.0, 75.0, 35.0)
    assert m == P.m_flow_max  # the pump's maximum


def test_heating_curve_and_thermostat_limits():
    P = room_thermostat.Params(curve=True)
    p, x = pack(P), room_thermostat.initial_state(P)
    T_sup, m = room_thermostat.step(1.0, x, p, 18.0, 21.0, -10.0)
    assert T_sup == pytest.approx(min(70.0, 21.0 + 1.2 * 31.0))
    assert m == pytest.approx(P.m_flow_max)  # 3 K below set-point: full flow
    T_sup, m = room_thermostat.step(1.0, x, p, 25.0, 21.0, 15.0)
    assert T_sup == pytest.approx(max(30.0, 21.0 + 1.2 * 6.0)) and m == 0.0


def test_header_volume_mixes_inflows_conservatively():
    P = pipe.Params(UA_loss=0.0)
    p, x = pack(P), np.array([40.0])
    for _ in range(2000):  # time constant V rho / m = 50 s
        pipe.step(1.0, x, p, 0.1 * CP * 70.0 + 0.1 * CP * 30.0, 0.2)
    assert x[0] == pytest.approx(50.0, abs=1e-6)
