"""House 2 (SF2): energy ledger, the null case's channels, the effects' signatures, realisations,
determinism. Short windows (0.5-2 days) so the file runs in seconds once numba has compiled."""
import csv
import json
import tomllib

import numpy as np
import pytest

from rigsim.house2 import suite
from rigsim.house2.daq import NAMES, channel_list
from rigsim.house2.model import Effects, draw_nuisance, simulate

JAN = "2021-01-12"
APR = "2021-04-21"
EXPECTED_IDS = {"no_missing_physics", "heat_loss", "sensor_offset", "sensor_lag",
                "heat_pump_capacity", "defrost_share", "port_valve_leakage",
                "collector_degradation", "collector_loop_loss", "slab_capacity",
                "unexplained_mismatch"}
SIZE_KEYS = {"storage_UA_W_per_K", "tag", "offset_K", "tau_s", "capacity_factor",
             "defrost_share", "leak_share", "eta0_factor", "UA_W_per_K", "factor"}
# channels no effect of the catalogue may move (weather, household, PV, fixed set-points)
BOUNDARY = ["S_TM_ambient", "DirectRadiation_W_per_m2", "DiffuseRadiation_W_per_m2",
            "P_elConsumption_kW", "PV_P_gen", "STM_HCVLaM_Set_degC"]


def col(r, name):
    return r.rec[:, NAMES.index(name)]


@pytest.fixture(scope="module")
def jan():
    nz = draw_nuisance(5)
    return nz, simulate(nz, Effects(), start=JAN, days=1.5)


@pytest.fixture(scope="module")
def apr():
    nz = draw_nuisance(5)
    return nz, simulate(nz, Effects(), start=APR, days=2.0)


def _eff(effects, start=JAN, days=1.5):
    return simulate(draw_nuisance(5), Effects.from_dict(effects), start=start, days=days)


def test_catalogue():
    assert len(suite.CASES) >= 8
    exp = [tuple(c["expected"]) for c in suite.CASES.values()]
    for name, c in suite.CASES.items():
        assert set(c["expected"]) <= EXPECTED_IDS, name
        assert set(c["sizes"]) <= SIZE_KEYS, name
        Effects.from_dict(c["effects"])
    assert ("no_missing_physics",) in exp and ("unexplained_mismatch",) in exp
    assert any(len(e) == 2 for e in exp)
    for v in ("heat_loss", "sensor_offset", "sensor_lag", "heat_pump_capacity", "defrost_share",
              "port_valve_leakage", "collector_degradation", "collector_loop_loss",
              "slab_capacity"):
        assert (v,) in exp, v


def test_ledger_closes(jan):
    _, r = jan
    led = r.ledger
    assert r.closure < 1e-9
    assert led["heat_pump_electricity_in_kWh"] > 20.0 and led["heat_pump_ambient_heat_in_kWh"] > 20.0
    assert led["heat_to_building_kWh"] > 100.0 and led["dhw_heat_kWh"] > 5.0
    for k in ("generator_losses_kWh", "pipe_and_header_losses_kWh", "storage_losses_kWh",
              "collector_losses_kWh"):
        assert led[k] > 0.0, k
    e_in = sum(led[k] for k in ("gas_in_kWh", "heat_pump_electricity_in_kWh",
                                "heat_pump_ambient_heat_in_kWh", "solar_absorbed_kWh"))
    e_out = sum(v for k, v in led.items() if not k.endswith("_in_kWh")
                and k not in ("solar_absorbed_kWh", "residual_kWh"))
    assert abs(e_in - e_out) < 1e-9 * e_in
    r2 = _eff({"heat_loss": {"storage_UA_W_per_K": 30.0},
               "port_valve_leakage": {"leak_share": 0.3},
               "collector_loop_loss": {"UA_W_per_K": 10.0}, "slab_capacity": {"factor": 0.5},
               "heat_pump_capacity": {"capacity_factor": 0.8},
               "defrost_share": {"defrost_share": 0.2}}, days=0.5)
    assert r2.closure < 1e-9


def test_physical_limits(jan):
    _, r = jan
    f = r.final
    assert f["tank_T_min"] >= f["T_cold"] - 1e-6 and f["tank_T_max"] < 90.0
    for n in NAMES:
        x = col(r, n)
        if n.startswith("TS_S_TM_BT_"):
            assert x.min() >= f["T_cold"] - 1e-6 and x.max() < 90.0, n
        if "FW" in n or n.endswith("l_per_min"):
            assert x.min() >= 0.0 and x.max() <= 42.0, n
    assert np.all(col(r, "HP_S_FW_HC")[col(r, "HP_S_FW_HC") > 0] >= 5.0 - 1e-9)
    # the unit heats only when its return is below 68 degC and the heat meter sees a 4-6 K
    # spread plus the back-up heater's share
    heating = (col(r, "HP_COP") > 0) & (col(r, "ASHP_AuxModulation_set") == 0)
    assert heating.sum() > 100
    spread = col(r, "HP_S_TM_VL")[heating] - col(r, "HP_S_TM_RL")[heating]
    assert 3.5 < np.median(spread) < 6.5


def test_null_case_files(tmp_path):
    meta = suite.make_case("null_a", tmp_path, days=0.5, realisation=2)
    d = tmp_path / "null_a"
    with open(d / "recording.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    spec = {r["channel"]: r for r in channel_list()}
    assert rows[0][0] == "t_s" and rows[0][1:] == [c for c in spec if c != "t_s"]
    assert len(rows) - 1 == 720 == meta["rows"]
    t = np.array([float(x[0]) for x in rows[1:]])
    assert np.all(np.abs(t - 60 * np.arange(t.size)) <= 0.5 + 1e-9)
    for j, name in enumerate(rows[0][1:], start=1):
        res = float(spec[name]["resolution"])
        vals = np.array([float(x[j]) for x in rows[1:]])
        assert np.all(np.abs(vals / res - np.round(vals / res)) < 1e-6), name
        unit = spec[name]["unit"]
        if unit == "°C":
            assert -30.0 < vals.min() and vals.max() < 95.0, name
        elif unit == "l/min":
            assert vals.min() >= 0.0 and vals.max() <= 42.0, name
        elif unit == "kW":
            assert -40.0 < vals.min() and vals.max() < 40.0, name
        elif unit == "1" and name != "HP_COP":
            assert set(np.unique(vals)) <= {0.0, 1.0}, name
        if name.startswith("TS_S_TM_BT_"):
            assert len(set(vals)) > 10, name
    assert set(np.unique([float(x[rows[0].index("EB_EB_power_kW_set")]) for x in rows[1:]])) <= {0.0, 20.0}
    cols = tomllib.loads((d / "columns.toml").read_text(encoding="utf-8"))
    assert set(cols["columns"]) == set(NAMES)
    assert cols["columns"]["TS_S_TM_BT_1"] == {"signal": "storage.T_sensor_1", "unit": "°C",
                                               "height": 0.05}
    assert cols["columns"]["ASHP_A_V3_TL"] == {"signal": "hp_valve.upper", "range": [0, 1, 1, 0]}
    assert cols["columns"]["EB_EB_power_kW_set"]["range"] == [2, 20, 2, 10]
    assert cols["columns"]["HP_P_elec_is"]["scale"] == -1
    assert "ports" not in cols   # five port pairs: their datasheet heights are the house file's
    m = json.loads((d / "meta.json").read_text(encoding="utf-8"))
    assert m["house"] == "house2" and m["expected"] == ["no_missing_physics"]
    assert m["ledger_closure"] < 1e-9 and "--house house2" in m["command"]
    assert m["nuisance"] == draw_nuisance(2)


def test_sensor_effects_move_only_their_channel(jan):
    _, b = jan
    for eff, tag in (({"sensor_offset": {"tag": "TS_S_TM_BT_4", "offset_K": -2.0}}, "TS_S_TM_BT_4"),
                     ({"sensor_lag": {"tag": "TS_S_TM_BT_9", "tau_s": 600.0}}, "TS_S_TM_BT_9")):
        r = _eff(eff)
        j = NAMES.index(tag)
        others = [i for i in range(len(NAMES)) if i != j]
        assert np.array_equal(r.rec[:, others], b.rec[:, others])
        if "sensor_offset" in eff:
            assert np.allclose(r.rec[:, j] - b.rec[:, j], -2.0)
        else:
            assert np.sum(np.abs(np.diff(r.rec[:, j]))) < 0.8 * np.sum(np.abs(np.diff(b.rec[:, j])))


def _boundary_unchanged(r, b):
    for n in BOUNDARY:
        assert np.array_equal(col(r, n), col(b, n)), n


def test_heat_loss(jan):
    _, b = jan
    r = _eff({"heat_loss": {"storage_UA_W_per_K": 30.0}})
    _boundary_unchanged(r, b)
    assert r.ledger["storage_losses_kWh"] > 2.5 * b.ledger["storage_losses_kWh"]
    assert (r.ledger["gas_in_kWh"] + r.ledger["heat_pump_electricity_in_kWh"]
            > b.ledger["gas_in_kWh"] + b.ledger["heat_pump_electricity_in_kWh"])


def test_heat_pump_capacity(jan):
    _, b = jan
    r = _eff({"heat_pump_capacity": {"capacity_factor": 0.8}})
    _boundary_unchanged(r, b)

    def ratio(x):   # heat meter over electricity while the compressor heats alone
        k = (col(x, "HP_COP") > 0) & (col(x, "ASHP_AuxModulation_set") == 0)
        return col(x, "HP_P_heat_Tot")[k].sum() / col(x, "HP_P_elec_is")[k].sum()

    assert ratio(r) < 0.88 * ratio(b)
    assert r.effect_size["hp_seasonal_cop"] < b.effect_size["hp_seasonal_cop"]


def test_defrost_share(jan):
    _, b = jan
    r = _eff({"defrost_share": {"defrost_share": 0.15}})
    _boundary_unchanged(r, b)
    assert 0.02 < b.effect_size["defrost_share_of_run_time"] < 0.04
    assert 0.12 < r.effect_size["defrost_share_of_run_time"] < 0.16

    def idle_share(x):  # the unit on, no flow (start delays and defrosts)
        on = col(x, "ASHP_ASHP_on") == 1
        return np.mean(col(x, "HP_S_FW_HC")[on] == 0.0)

    assert idle_share(r) > idle_share(b) + 0.06


def test_port_valve_leakage(jan):
    _, b = jan
    r = _eff({"port_valve_leakage": {"leak_share": 0.25}})
    _boundary_unchanged(r, b)
    assert r.effect_size["hp_flow_to_other_port_pair_kg"] > 20 * max(
        b.effect_size["hp_flow_to_other_port_pair_kg"], 1.0)

    def lower_return_excess(x):   # valve LOWER, unit flowing: its return above sensor 2
        k = (col(x, "ASHP_A_V3_TL") == 1) & (col(x, "HP_S_FW_HC") > 0)
        return np.mean(col(x, "HP_S_TM_RL")[k] - col(x, "TS_S_TM_BT_2")[k])

    assert lower_return_excess(r) > lower_return_excess(b) + 1.0


def test_slab_capacity(jan):
    _, b = jan
    r = _eff({"slab_capacity": {"factor": 0.4}}, days=1.5)
    _boundary_unchanged(r, b)

    def swing(x):
        T = col(x, "S_TM_room")
        return np.percentile(T, 95) - np.percentile(T, 5)

    assert swing(r) > swing(b) + 0.2


def test_solar_effects(apr):
    _, b = apr
    assert b.effect_size["solar_heat_kWh"] > 3.0
    d = _eff({"collector_degradation": {"eta0_factor": 0.6}}, start=APR, days=2.0)
    _boundary_unchanged(d, b)
    assert d.ledger["solar_absorbed_kWh"] == pytest.approx(0.6 * b.ledger["solar_absorbed_kWh"])
    assert d.effect_size["solar_heat_kWh"] < 0.75 * b.effect_size["solar_heat_kWh"]
    # a degraded collector reaches the pump's start difference less often
    assert d.effect_size["solar_pump_hours"] < 0.8 * b.effect_size["solar_pump_hours"]
    L = _eff({"collector_loop_loss": {"UA_W_per_K": 8.0}}, start=APR, days=2.0)
    _boundary_unchanged(L, b)
    assert L.ledger["solar_absorbed_kWh"] == b.ledger["solar_absorbed_kWh"]
    assert L.effect_size["solar_heat_kWh"] < 0.8 * b.effect_size["solar_heat_kWh"]
    assert L.ledger["pipe_and_header_losses_kWh"] > b.ledger["pipe_and_header_losses_kWh"] + 1.0
    # the loop loses its heat on the way: the pump runs about as long as without the effect
    assert L.effect_size["solar_pump_hours"] > 0.8 * b.effect_size["solar_pump_hours"]


# realisations (differ, reproduce): tests/rigsim/test_suite.py, for both houses
