"""A small (1-day) labsim recording of each case type is read by profiles.recording (the one reader)
through its columns file, and by the diagnosis's loader in the twin's units; meta.json holds the truth."""
import json

import numpy as np
import pytest

from plant.diagnose import recording_io
from labsim.suite import CASES, make_case
from profiles.recording import read_recording

TYPES = ["no_effect", "idle_flow_large", "heat_loss_45", "inlet_mixing_120", "sensor_lag_300",
         "sensor_offset_minus_3", "transport_delay_180", "valve_leak_8", "fouled_dhw_coil", "boiler_fouled",
         "pair_heat_loss_offset"]


def test_the_suite_holds_the_cases_the_brief_asks_for():
    assert len(CASES) >= 12
    expected = {e for _, _, exp, _ in CASES.values() for e in exp}
    for effect in ("idle_generator_flow", "heat_loss", "storage_mixing", "sensor_lag", "sensor_offset",
                   "transport_delay", "valve_leakage", "no_missing_physics", "unexplained_mismatch"):
        assert effect in expected
    assert sum(len(exp) == 2 for _, _, exp, _ in CASES.values()) >= 2  # pairs


@pytest.mark.parametrize("case", TYPES)
def test_a_day_of_each_case_type_is_readable(case, tmp_path):
    meta = make_case(case, tmp_path / case, days=1.0)
    rec = read_recording(tmp_path / case)
    assert rec.start == "2021-01-10" and len(rec.time) == 1440
    assert rec.signals["TS_S_TM_BT_10"] == "storage.T_sensor_10" and rec.units["HK_S_FW_VL"] == "l/min"
    assert rec.units["CHP_CMD_MOD"] == "%" and rec.signals["CB_CMD_MOD"] == "boiler.U_set"  # 0-100 % onto 0-10 V
    assert "CB_CMD_U" not in rec.signals and rec.meta["columns"]["TS_S_TM_BT_1"]["height"] == pytest.approx(0.12 / 1.63, abs=1e-4)
    assert np.isfinite(rec.values).all()
    s = recording_io.load(tmp_path / case)  # catalogue units
    assert 0.0 <= np.nanmax(s.data["chp.y_set"]) <= 1.0 and np.nanmax(s.data["boiler.U_set"]) <= 10.0
    assert np.allclose(s.data["boiler.U_set"], rec.column("CB_CMD_U"), atol=0.05)  # the range map gives the V channel
    assert s.sensor_overrides()["storage.sensor_heights"][0] == pytest.approx(0.12 / 1.63, abs=1e-4)
    assert s.ports["storage"] == pytest.approx({"top": 1.55 / 1.63, "bottom": 0.08 / 1.63}, abs=1e-4)
    assert 10.0 < np.nanmedian(s.data["storage.T_sensor_5"]) < 90.0
    m = json.loads((tmp_path / case / "meta.json").read_text())
    assert m["case"] == case and m["expected"] == CASES[case][2] and m["effects"] == CASES[case][1]
    assert abs(meta["ledger_closure"]) < 1e-3
    if case.startswith("idle_flow"):
        assert meta["effect_size"]["idle_chp_flow_mean_kg_s"] > 0.005
    if case == "no_effect":
        assert meta["effect_size"].get("idle_chp_flow_mean_kg_s", 0.0) == 0.0
