"""Electric heating rod: thermostat hysteresis, the P_set limit and stages, the energy balance of a
house with a rod in its storage (to round-off), bad links reported."""
import numpy as np
import pytest

from plant.component import pack
from plant.components import electric_heater as eh
from plant.declaration import HOUSES
from plant.errors import ConfigError
from plant.house import load_house
from plant.water import CP, RHO

ROD = '''
[house]
name = "house1_rod"
base = "{base}"

[heater]
kind = "electric_heater"
storage = "storage"
height = 0.80
{extra}
'''


def _variant(tmp_path, extra="", name="rod.toml"):
    path = tmp_path / name
    path.write_text(ROD.format(base=HOUSES / "house1.toml", extra=extra))
    return path


def _p(**kw):
    from dataclasses import replace

    return np.append(pack(replace(eh.Params(), **kw)), 1.0)


def test_thermostat_hysteresis():
    """Opens at T_max = 90, stays open down to 85, closes below 85, holds in between."""
    p, x = _p(), eh.initial_state(None)
    seq = [(60.0, 6000.0), (89.9, 6000.0), (90.0, 0.0), (88.0, 0.0), (85.0, 0.0), (84.99, 6000.0),
           (87.0, 6000.0), (89.99, 6000.0), (90.5, 0.0), (86.0, 0.0)]
    for T, want in seq:
        assert eh.power(x, p, 1.0, 6000.0, T) == want, T
    assert eh.power(x, p, 0.0, 6000.0, 40.0) == 0.0  # relay blocked
    assert x[eh.X.thermostat] == 1.0  # the thermostat follows the layer even while blocked


def test_power_limited_to_p_set_and_stages():
    p, x = _p(), eh.initial_state(None)
    assert eh.power(x, p, 1.0, 2500.0, 50.0) == 2500.0
    assert eh.power(x, p, 1.0, 9000.0, 50.0) == 6000.0
    assert eh.power(x, p, 1.0, -100.0, 50.0) == 0.0
    staged = _p(n_stages=3)
    got = [eh.power(x, staged, 1.0, P, 50.0) for P in (1999.0, 2000.0, 3999.0, 4000.0, 5999.0, 6000.0, 7000.0)]
    assert got == [0.0, 2000.0, 2000.0, 4000.0, 4000.0, 6000.0, 6000.0]


def test_rod_in_house1_closes_the_ledger_and_limits_to_p_set(tmp_path):
    house = load_house(_variant(tmp_path), start="2021-01-10")
    assert house.get("heater.P_set") == 6000.0  # written by the kind: a plain relay gives full power
    house.set("heater.on", 1.0)
    house.step(3600.0)
    assert house.get("heater.P_el") == -6000.0 and house.get("heater.on_effective") == 1.0
    house.set("heater.P_set", 2500.0)  # PV-surplus mode
    house.step(3600.0)
    assert house.get("heater.Q_flow") == 2500.0 and house.get("heater.P_el") == -2500.0
    L = house.ledger()
    E = (6000.0 + 2500.0) * 3600.0
    assert L["heat_heater"] == pytest.approx(E, rel=1e-12)
    assert L["el_heater"] == pytest.approx(-E, rel=1e-12)
    assert house.get("heater.E_el") == pytest.approx(-E, rel=1e-12)
    assert abs(L["residual"]) < 1e-9 * (L["fuel"] + E)
    assert L["generator_losses"] == pytest.approx(L["fuel"] - L["el_net"] - L["heat_generators"])


IDLE = (("heater.on", 1.0), ("boiler.U_set", 0.0), ("chp.on", 0.0), ("mixer.m_flow_set", 0.0),
        ("dhw_pump.on", 0.0))  # nothing flows through the switch: the storage alone with its rod


def test_rod_heat_goes_into_its_layer_exactly(tmp_path):
    """The storage's energy rises by the rod's heat minus its losses, to round-off."""
    house = load_house(_variant(tmp_path), start="2021-01-10")
    for name, v in IDLE:
        house.set(name, v)
    E0 = house.get("storage.E_stored")
    house.step(3600.0)
    L = house.ledger()
    dE = house.get("storage.E_stored") - E0
    assert house.get("storage.m_flow") == 0.0
    assert dE == pytest.approx(6000.0 * 3600.0 - L["loss_storage"], rel=1e-12)


def test_thermostat_in_the_house_holds_the_layer_below_t_max(tmp_path):
    """A 60 kW rod in an idle storage: its layer reaches 90 degC, then cycles between 85 and 90."""
    house = load_house(_variant(tmp_path, "P_nom = 60000.0"), start="2021-01-10")
    for name, v in IDLE:
        house.set(name, v)
    layer = 40 - 1 - int(0.80 / 1.63 * 40)
    T, th = [], []
    for _ in range(3 * 3600 // 5):
        T.append(house.state("storage")[layer])  # what the thermostat sees at the step's start
        house.step(5.0)
        th.append(house.get("heater.thermostat"))
    T, th = np.array(T), np.array(th)
    opened = np.flatnonzero(np.diff(th) < 0) + 1
    closed = np.flatnonzero(np.diff(th) > 0) + 1
    assert len(opened) >= 2 and len(closed) >= 1  # it cycles
    dT_step = 60000.0 * 5.0 / (RHO * 0.8 / 40 * CP)  # the most one step can add to the layer
    assert T.max() < 90.0 + dT_step
    assert all(T[i] >= 90.0 for i in opened) and all(T[i] < 85.0 for i in closed)
    assert all(85.0 <= T[i] < 90.0 for i in range(len(th)) if i not in opened and i not in closed
               and i > 0 and th[i] != th[i - 1])  # no other switching


@pytest.mark.parametrize("old, new, message", [
    ('storage = "storage"', 'storage = "zone"', "cannot be used as storage"),
    ('height = 0.80', 'height = 2.5', "height = 2.5: outside the storage 'storage'; allowed 0 … 1.63 m"),
    ('storage = "storage"', 'storage = "nowhere"', "no such instance"),
])
def test_bad_links_are_reported(tmp_path, old, new, message):
    path = tmp_path / "bad.toml"
    path.write_text(ROD.format(base=HOUSES / "house1.toml", extra="").replace(old, new))
    with pytest.raises(ConfigError) as err:
        load_house(path)
    assert "[heater]" in str(err.value) and message in str(err.value)
