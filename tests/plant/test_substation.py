"""District-heating substation: the counterflow effectiveness against an integrated exchanger and
the formula, extraction and feed-in through one instance on house 1's switch with the ledger
closed to round-off, the sign convention, bad declarations."""
import math
from dataclasses import replace

import numpy as np
import pytest

from plant.component import pack
from plant.components import substation as sub
from plant.declaration import HOUSES
from plant.errors import ConfigError
from plant.house import load_house
from plant.water import CP

DH = '''
[house]
name = "house1_dh"
base = "{base}"

[substation]
kind = "substation"
{extra}

[switch]
generators = ["boiler", "chp", "substation"]
consumers = ["mixer", "dhw_pump", "substation"]
'''


def _variant(tmp_path, extra="", name="dh.toml"):
    path = tmp_path / name
    path.write_text(DH.format(base=HOUSES / "house1.toml", extra=extra))
    return path


def _integrated_counterflow(UA, C_hot, C_cold, T_hot_in, T_cold_in, n=4000):
    """Outlet temperatures of a counterflow exchanger by integrating its two ODEs along the
    length (RK4; the cold side enters at the far end: shooting on its unknown outlet, exact for a
    linear system with two trial solutions)."""
    def shoot(T_cold_out):
        y = np.array([T_hot_in, T_cold_out])
        dx = 1.0 / n
        f = lambda y: np.array([-UA / C_hot * (y[0] - y[1]), -UA / C_cold * (y[0] - y[1])])  # noqa: E731
        for _ in range(n):
            k1 = f(y)
            k2 = f(y + dx / 2 * k1)
            k3 = f(y + dx / 2 * k2)
            k4 = f(y + dx * k3)
            y = y + dx / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return y  # (hot out, cold at the far end)
    a, b = shoot(T_cold_in), shoot(T_hot_in)
    s = (T_cold_in - a[1]) / (b[1] - a[1])  # the cold inlet condition, linear in the guess
    T_cold_out = T_cold_in + s * (T_hot_in - T_cold_in)
    return shoot(T_cold_out)[0], T_cold_out


def _formula(UA, C1, C2):
    C_min, C_max = min(C1, C2), max(C1, C2)
    ntu, cr = UA / C_min, C_min / C_max
    if cr == 1.0:
        return ntu / (1 + ntu)
    return (1 - math.exp(-ntu * (1 - cr))) / (1 - cr * math.exp(-ntu * (1 - cr)))


@pytest.mark.parametrize("m_house, m_grid", [(0.15, 0.10), (0.10, 0.10), (0.05, 0.20), (0.25, 0.02)])
def test_effectiveness_is_the_counterflow_exchangers(m_house, m_grid):
    p = pack(sub.Params())
    Q, T_house_out, T_grid_out, eps = sub.exchange(p, m_house, m_grid, 35.0, 70.0)
    T_grid_ref, T_house_ref = _integrated_counterflow(2945.0, m_grid * CP, m_house * CP, 70.0, 35.0)
    assert T_house_out == pytest.approx(T_house_ref, abs=1e-6)
    assert T_grid_out == pytest.approx(T_grid_ref, abs=1e-6)
    assert eps == pytest.approx(_formula(2945.0, m_house * CP, m_grid * CP), rel=1e-9)
    assert Q == pytest.approx(m_house * CP * (T_house_out - 35.0), rel=1e-12)
    assert Q == pytest.approx(m_grid * CP * (70.0 - T_grid_out), rel=1e-12)
    fixed = pack(replace(sub.Params(), epsilon=0.8))
    assert sub.exchange(fixed, m_house, m_grid, 35.0, 70.0)[0] == pytest.approx(0.8 * min(m_house, m_grid) * CP * 35.0)
    assert sub.exchange(p, m_house, 0.0, 35.0, 70.0) == (0.0, 35.0, 70.0, 0.0)  # no grid flow: no heat


def test_extraction_and_feed_in_through_one_instance(tmp_path):
    """Extraction, then feed-in, on house 1's switch (boiler and CHP off): the heat meters, the
    signs and the ledger (extracted heat = fuel = heat, fed-in heat = building) to round-off."""
    house = load_house(_variant(tmp_path), start="2021-01-10")
    assert house.get("substation.T_grid_sup") == 70.0 and house.get("substation.T_grid_ret") == 40.0
    house.set("boiler.U_set", 0.0)
    house.set("chp.on", 0.0)
    house.set("substation.m_flow_set", 0.15)  # + extraction
    house.set("substation.m_flow_grid_set", 0.10)
    house.step(3600.0)
    g = {n: house.get(f"substation.{n}") for n in ("m_flow", "m_flow_grid", "Q_flow", "T_sup", "T_ret",
                                                   "T_grid_in", "T_grid_out", "E_extracted", "E_fed_in")}
    assert g["m_flow"] == 0.15 and g["m_flow_grid"] == 0.10 and g["Q_flow"] > 0.0
    assert g["T_grid_in"] == 70.0 and g["T_sup"] > g["T_ret"] and g["T_grid_out"] < 70.0
    assert g["Q_flow"] == pytest.approx(0.15 * CP * (g["T_sup"] - g["T_ret"]), rel=1e-12)
    assert g["Q_flow"] == pytest.approx(0.10 * CP * (g["T_grid_in"] - g["T_grid_out"]), rel=1e-12)
    assert g["E_extracted"] > 3e6 and g["E_fed_in"] == 0.0
    house.set("substation.m_flow_set", -0.10)  # - feed-in
    house.step(3600.0)
    f = {n: house.get(f"substation.{n}") for n in g}
    assert f["m_flow"] == -0.10 and f["m_flow_grid"] == -0.10 and f["Q_flow"] < 0.0
    assert f["T_grid_in"] == 40.0 and f["T_grid_out"] > 40.0 and f["T_sup"] > f["T_ret"]
    assert -f["Q_flow"] == pytest.approx(0.10 * CP * (f["T_sup"] - f["T_ret"]), rel=1e-12)
    assert f["E_extracted"] == g["E_extracted"] and f["E_fed_in"] > 3e6
    L = house.ledger()
    assert L["fuel_substation"] == pytest.approx(f["E_extracted"], rel=1e-12)
    assert L["heat_substation"] == L["fuel_substation"]
    assert L["building_substation"] == pytest.approx(f["E_fed_in"], rel=1e-12)
    assert abs(L["residual"]) < 1e-12 * (L["fuel"] + L["building_substation"])


def test_effectiveness_in_the_house_matches_the_formula(tmp_path):
    """Steady set-points for an hour: the exchanger's effectiveness read off the signals is the
    analytic counterflow value (the 1 % of the issue; it agrees to round-off)."""
    house = load_house(_variant(tmp_path), start="2021-01-10")
    house.set("substation.m_flow_set", 0.12)
    house.set("substation.m_flow_grid_set", 0.08)
    house.set("substation.T_grid_sup", 75.0)
    house.step(3600.0)
    T_in, T_out = house.get("substation.T_ret"), house.get("substation.T_sup")
    eps = house.get("substation.Q_flow") / (0.08 * CP * (75.0 - T_in))
    assert eps == pytest.approx(_formula(2945.0, 0.12 * CP, 0.08 * CP), rel=1e-2)
    assert eps == pytest.approx(house.get("substation.epsilon"), rel=1e-12)
    T_grid_ref, T_house_ref = _integrated_counterflow(2945.0, 0.08 * CP, 0.12 * CP, 75.0, T_in)
    assert T_out == pytest.approx(T_house_ref, abs=1e-4)


def test_sign_convention(tmp_path):
    """Positive = extraction (the switch code's convention, §8.2): + flow brings heat in, -
    flow gives it away, and the flows are clipped at the pump maxima."""
    house = load_house(_variant(tmp_path, "m_flow_max = 0.2"), start="2021-01-10")
    house.set("substation.m_flow_grid_set", 5.0)  # above m_flow_grid_max = 1 kg/s
    for m_set, want in ((0.5, 0.2), (-0.5, -0.2), (0.0, 0.0)):
        house.set("substation.m_flow_set", m_set)
        house.step(60.0)
        assert house.get("substation.m_flow") == want
        assert house.get("substation.m_flow_grid") == math.copysign(1.0, m_set) * 1.0
        assert np.sign(house.get("substation.Q_flow")) == np.sign(want)
    desc = house.catalogue.signal("substation.m_flow_set").description
    assert "> 0 extraction" in desc and "< 0 feed-in" in desc


def test_extraction_only_on_a_branch(tmp_path):
    """A substation piped straight to the storage (the SF3/SF4 switch without generators) extracts;
    a negative set-point moves nothing there (no consumer side)."""
    text = DH.format(base=HOUSES / "house1.toml", extra="").replace(
        '[switch]\ngenerators = ["boiler", "chp", "substation"]\nconsumers = ["mixer", "dhw_pump", "substation"]\n',
        '[switch]\ngenerators = ["boiler", "chp"]\nconsumers = ["mixer", "dhw_pump"]\n\n'  # off house 1's switch
        '[dh_branch]\nkind = "branch"\ngenerator = "substation"\nstorage = "storage"\nsupply = 1.5\nreturn = 0.1\n')
    path = tmp_path / "branch.toml"
    path.write_text(text)
    house = load_house(path, start="2021-01-10")
    house.set("substation.m_flow_set", 0.1)
    house.set("substation.m_flow_grid_set", 0.1)
    house.step(3600.0)
    assert house.get("substation.Q_flow") > 0.0
    house.set("substation.m_flow_set", -0.1)
    house.step(600.0)
    assert house.get("substation.m_flow") == 0.0 and house.get("substation.Q_flow") == 0.0
    L = house.ledger()
    assert abs(L["residual"]) < 1e-12 * L["fuel"]


@pytest.mark.parametrize("old, new, message", [
    ('generators = ["boiler", "chp", "substation"]\nconsumers = ["mixer", "dhw_pump", "substation"]',
     'generators = ["boiler", "chp"]\nconsumers = ["mixer", "dhw_pump"]',
     "a substation connected to nothing; list it in a coupling point's generators or consumers"),
    ('consumers = ["mixer", "dhw_pump", "substation"]', 'consumers = ["mixer", "dhw_pump", "substation", "substation"]',
     "port connected twice"),
    ('kind = "substation"', 'kind = "substation"\nepsilon = 1.5', "epsilon = 1.5: out of range; allowed -1.0 … 1.0"),
    ('kind = "substation"', 'kind = "substation"\nstorage = "storage"', "storage: not a parameter or link"),
])
def test_bad_declarations_are_reported(tmp_path, old, new, message):
    path = tmp_path / "bad.toml"
    path.write_text(DH.format(base=HOUSES / "house1.toml", extra="").replace(old, new))
    with pytest.raises(ConfigError) as err:
        load_house(path)
    assert message in str(err.value)


def test_a_feed_in_only_substation_is_a_consumer(tmp_path):
    """The kind has both roles: named only among the consumers it can feed in, never extract."""
    path = tmp_path / "feed_in.toml"
    path.write_text(DH.format(base=HOUSES / "house1.toml", extra="").replace(
        'generators = ["boiler", "chp", "substation"]', 'generators = ["boiler", "chp"]'))
    house = load_house(path, controller="external")
    house.set("substation.m_flow_set", -0.1)
    house.set("substation.m_flow_grid_set", 0.1)
    house.step(600.0)
    assert house.get("substation.Q_flow") < 0.0  # heat went to the grid
    L = house.ledger()
    assert L["building_substation"] > 1e6  # J fed in over the 10 minutes
    assert abs(L["residual"]) < 1e-9 * L["heat_building"]  # no fuel burnt: closed against the heat moved
