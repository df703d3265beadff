"""PV generator (plant/components/pv.py): the power formula, limits, the yearly specific yield of
Munich 2021, and a house with a PV array (ledger: electricity only)."""
from pathlib import Path

import pytest

from plant import sun
from plant.component import pack
from plant.components import pv
from plant.errors import ConfigError
from plant.house import load_house
from profiles import loaders

HOUSES = Path(__file__).resolve().parents[2] / "plant" / "houses"
P = pv.Params()


def test_power_at_stc_noct_and_night():
    p = pack(P)
    # cells at 25 degC under 1000 W/m2: rated power x PR
    T_air = 25.0 - (P.T_NOCT - 20.0) * 1000.0 / 800.0
    P_el, T_cell = pv.power(p, 1000.0, T_air)
    assert T_cell == pytest.approx(25.0) and P_el == pytest.approx(P.P_peak * P.PR)
    # NOCT conditions (800 W/m2, 20 degC air): cells at T_NOCT, derated by gamma (T_NOCT - 25)
    P_el, T_cell = pv.power(p, 800.0, 20.0)
    assert T_cell == pytest.approx(P.T_NOCT)
    assert P_el == pytest.approx(P.P_peak * 0.8 * P.PR * (1 + P.gamma * (P.T_NOCT - 25.0)))
    assert pv.power(p, 0.0, -10.0)[0] == 0.0
    assert pv.power(p, -5.0, 10.0)[0] == 0.0  # never negative


def test_specific_yield_of_munich_2021():
    """Reference: PVGIS gives about 1100-1200 kWh/kWp a for an optimally inclined, south-facing
    crystalline array in Munich with 14 % system losses; the isotropic sky and our losses
    (PR 0.86 plus the temperature derate) should land in 1000-1200 kWh/kWp."""
    p = pack(P)
    w = loaders.weather()
    E_dir, E_dif, T_air, step = w["E_dir"].values, w["E_dif"].values, w["T_air"].values, w["E_dir"].step
    E = 0.0
    for k in range(len(E_dir)):
        b, d, _ = sun.plane(k * step, E_dir[k], E_dif[k], P.latitude, P.longitude, P.tilt, P.azimuth, P.albedo)
        E += pv.power(p, b + d, T_air[k])[0] * step
    specific = E / 3.6e6 / (P.P_peak / 1000.0)
    assert 1000.0 < specific < 1200.0


PV_HOUSE = '''
[house]
name = "house1_pv"
base = "house1"

[pv]
kind = "pv"
P_peak = 10000.0
'''


def test_house_with_pv_books_electricity_only(tmp_path):
    path = tmp_path / "pv.toml"
    path.write_text(PV_HOUSE.replace('base = "house1"', f'base = "{HOUSES / "house1.toml"}"'))
    house = load_house(path, start="2021-06-15")
    times, rows = house.run(86400.0, dt=5.0, out_interval=300.0)
    names = house.catalogue.names
    L = house.ledger()
    assert L["closure"] < 1e-9
    assert L["el_pv"] == pytest.approx(house.get("pv.E_el"), rel=1e-12)
    assert "fuel_pv" not in L and "heat_pv" not in L
    kwh = house.get("pv.E_el") / 3.6e6
    assert 30.0 < kwh < 80.0  # 10 kWp on a sunny June day: 3-8 kWh/kWp
    P_el = rows[:, names.index("pv.P_el")]
    assert P_el.min() == 0.0 and P_el.max() < P.P_peak * P.PR
    night = rows[:, names.index("pv.G_plane")] == 0.0
    assert night.any() and (P_el[night] == 0.0).all()


def test_bad_parameters_are_reported(tmp_path):
    path = tmp_path / "pv.toml"
    text = PV_HOUSE.replace('base = "house1"', f'base = "{HOUSES / "house1.toml"}"')
    path.write_text(text.replace("P_peak = 10000.0", "P_peak = -1.0\nPR = 1.5\nkWp = 10"))
    with pytest.raises(ConfigError) as err:
        load_house(path)
    text = str(err.value)
    assert "P_peak = -1.0: out of range" in text and "PR = 1.5: out of range" in text
    assert "kWp: not a parameter or link of a pv" in text
