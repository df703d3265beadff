"""Recording generator and the shipped recording."""
import json
from pathlib import Path

import numpy as np
import pytest

from plant.catalogue import CATALOGUE
from plant.truth.recording import COLUMNS, NOISE, make_recording
from profiles.recording import read_recording

SHIPPED = Path(__file__).resolve().parents[2] / "profiles" / "recordings" / "concealed_idle_flow"


@pytest.fixture(scope="module")
def rec(tmp_path_factory):
    out = tmp_path_factory.mktemp("rec")
    meta = make_recording("concealed_idle_flow", out, days=0.5, start="2021-01-10", seed=3)
    return out, meta


def test_declared_columns_units_and_mapping(rec):
    out, meta = rec
    rec = read_recording(out)
    t, data, units, start = rec.time, rec.data, rec.units, rec.start
    assert start == "2021-01-10" and list(data) == [c[0] for c in COLUMNS]
    for col, sig, unit, _ in COLUMNS:
        assert sig in CATALOGUE and units[col] == unit and rec.signals[col] == sig
    assert len(t) == meta["rows"] == 720
    for col in ("chp.on", "chp.y_set", "boiler.U_set", "dhw_pump.on", "mixer.T_sup_set", "mixer.m_flow_set"):
        assert col in [c[1] for c in COLUMNS]  # replay inputs
    assert "chp.m_flow" not in [c[1] for c in COLUMNS]  # no flow meter in the CHP branch


def test_jitter_noise_and_quantisation(rec):
    out, meta = rec
    rec = read_recording(out)
    t, data = rec.time, rec.data
    d = np.diff(t)
    assert np.all(d > 0) and d.std() > 0.3 and np.abs(d - 60).max() <= 2 * 2 + 1
    assert np.any(np.abs(t - 60 * np.round(t / 60)) > 0.01)  # not on a grid
    for col in ("TS_S_TM_BT_5", "CHP_S_TM_VL"):
        v = data[col]
        assert np.allclose(v * 10, np.round(v * 10), atol=1e-6)  # 0.1 K
    # noise level: second differences of the slowly varying room temperature ~ sqrt(6)*0.07 K
    r = np.diff(data["ZONE_S_TM_ROOM"], 2)
    assert 0.08 < r.std() < 0.4
    assert meta["noise"]["temperature_K"] == NOISE["T"][0]


def test_nominal_case_uses_the_twin(tmp_path):
    meta = make_recording("nominal", tmp_path, days=0.1, seed=1)
    assert "ideal twin" in meta["truth_parameters"]["plant"] and meta["ledger_closure"] < 1e-6


def test_shipped_recording_reads_back_and_matches_its_meta():
    meta = json.loads((SHIPPED / "meta.json").read_text())
    rec = read_recording(SHIPPED)
    t, data, start = rec.time, rec.data, rec.start
    assert len(t) == meta["rows"] == 10080 and start == meta["start"] == "2021-01-10"
    assert meta["case"] == "concealed_idle_flow" and meta["seed"] == 1
    e = meta["effect"]
    assert 0.015 < e["idle_chp_flow_mean_kg_s"] < 0.1
    assert 0.25 < e["idle_chp_share_of_heating_primary_flow"] < 0.5
    assert 0.02 < abs(e["chp_heat_error_ideal_twin_vs_truth"]) < 0.1  # several %
    readme = (SHIPPED / "README.md").read_text()
    assert meta["command"] in readme and f"{e['idle_chp_flow_mean_kg_s']:.3f}" in readme
    assert data["CHP_S_TM_VL"].max() < 95 and np.nanmax(data["CHP_P_el"]) > 1.5
