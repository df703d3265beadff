"""The case files: recording.csv, columns.toml, meta.json, and realisations."""
import csv
import json
import tomllib

import pytest

from rigsim import model, suite
from rigsim.house2 import model as model2
from rigsim.house2 import suite as suite2
from rigsim.house3 import model as model3
from rigsim.house3 import suite as suite3
from rigsim.daq import NAMES
from rigsim.tables import channel_list

EXPECTED_IDS = {"no_missing_physics", "idle_generator_flow", "heat_loss", "storage_mixing",
                "sensor_lag", "sensor_offset", "transport_delay", "valve_leakage",
                "unexplained_mismatch"}
SIZE_KEYS = {"storage_UA_W_per_K", "plume_litres", "tag", "tau_s", "offset_K", "delay_s",
             "leak_share"}


def test_cases_catalogue():
    assert len(suite.CASES) == 20
    assert {"null_a", "null_b"} <= set(suite.CASES)
    for name, c in suite.CASES.items():
        assert set(c["expected"]) <= EXPECTED_IDS, name
        assert set(c["sizes"]) <= SIZE_KEYS, name
    assert sum(c["expected"] == ["unexplained_mismatch"] for c in suite.CASES.values()) == 2
    assert sum(len(c["expected"]) == 2 for c in suite.CASES.values()) == 2


@pytest.fixture(scope="module")
def case_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("rs")
    meta = suite.make_case("pair_idle_lag", out, days=0.5, realisation=2)
    return out / "pair_idle_lag", meta


def test_case_files_and_contract(case_dir):
    d, meta = case_dir
    with open(d / "recording.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    header = rows[0]
    assert header[0] == "t_s"
    assert header[1:] == [r["channel"] for r in channel_list() if r["channel"] != "t_s"]
    assert len(rows) - 1 == 720 == meta["rows"]
    t = [float(r[0]) for r in rows[1:]]
    res = {r["channel"]: float(r["resolution"]) for r in channel_list()}
    for j, name in enumerate(header[1:], start=1):
        vals = [float(r[j]) for r in rows[1:]]
        assert all(abs(v / res[name] - round(v / res[name])) < 1e-6 for v in vals), name
        if name.startswith("BT_T"):
            assert len(set(vals)) > 10, name
    assert all(abs(ti - 60 * k) <= 0.5 + 1e-9 for k, ti in enumerate(t))
    cols = tomllib.loads((d / "columns.toml").read_text(encoding="utf-8"))
    assert cols["recording"] == {"start": "2021-01-10", "file": "recording.csv", "time": "t_s"}
    assert cols["ports"]["storage"] == {"top": 0.9509, "bottom": 0.0491}
    assert set(cols["columns"]) == set(NAMES)
    assert cols["columns"]["BT_T01"] == {"signal": "storage.T_sensor_1", "unit": "°C",
                                         "height": 0.0613}
    assert cols["columns"]["CB_MOD_SET"] == {"signal": "boiler.U_set", "range": [0, 100, 0, 10]}
    assert cols["columns"]["HC_FLOW"] == {"signal": "mixer.m_flow", "unit": "l/min"}
    assert cols["columns"]["WWS_T2"]["signal"] == "dhw_storage.T_sensor_5"
    m = json.loads((d / "meta.json").read_text(encoding="utf-8"))
    for k in ("simulator", "case", "description", "realisation", "nuisance", "effects",
              "expected", "sizes", "effect_size", "ledger", "ledger_closure", "rows",
              "generation_wall_s", "command"):
        assert k in m, k
    assert m["simulator"] == "rigsim" and m["realisation"] == 2
    assert m["expected"] == ["idle_generator_flow", "sensor_lag"]
    assert m["sizes"] == {"tag": "BT_T10", "tau_s": 600.0}
    assert m["effect_size"]["idle_chp_flow_mean_kg_s"] >= 0.0
    assert m["ledger_closure"] < 1e-6
    assert "rigsim.suite" in m["command"]


@pytest.mark.parametrize("m, s, case", [(model, suite, "null_a"), (model2, suite2, "heat_loss_30"),
                                        (model3, suite3, "ground_collector_degradation_700")],
                         ids=["house1", "house2", "house3"])
def test_realisations_differ_and_reproduce(tmp_path, m, s, case):
    """Every house's suite: a realisation reproduces its nuisance and recording, another differs."""
    a, b = m.draw_nuisance(0), m.draw_nuisance(1)
    assert a != b and m.draw_nuisance(1) == b
    m1 = s.make_case(case, tmp_path / "x", days=0.1, realisation=3)
    m2 = s.make_case(case, tmp_path / "y", days=0.1, realisation=3)
    assert m1["nuisance"] == m2["nuisance"]
    rec = {k: (tmp_path / k / case / "recording.csv").read_bytes() for k in "xy"}
    assert rec["x"] == rec["y"]
    m3 = s.make_case(case, tmp_path / "z", days=0.1, realisation=4)
    assert m3["nuisance"] != m1["nuisance"]
    assert (tmp_path / "z" / case / "recording.csv").read_bytes() != rec["x"]
