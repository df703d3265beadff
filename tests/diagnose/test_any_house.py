"""The diagnosis on houses other than house 1: house 2's recording from the clean-room rig
simulator, and a house file written for this test (not shipped), each through its derived cut
and its own roles."""
import numpy as np

from plant.diagnose import diagnose, recording_io
from plant.diagnose.roles import of as roles_of
from plant.house import load_house
from plant.housefile import HOUSES


def test_a_house2_rig_recording_gets_a_verdict_on_house2s_own_terms(tmp_path):
    from rigsim.house2.suite import make_case

    make_case("null_a", tmp_path, days=1.0, start="2021-01-10", realisation=0)
    d = tmp_path / "null_a"
    rec = recording_io.load(d, d / "columns.toml", house="house2")
    rep = diagnose(rec, house="house2", log=lambda *a: None, plots=False, jobs=1)
    assert rep["verdict"] in ("no_missing_physics", "missing_physics", "unexplained_mismatch")
    assert rep["locate"]["replay"]["plant"] == "house2_cut_circuit"
    assert rep["locate"]["replay"]["boundaries"]["mixer.T_return"] == "mixer.T_ret"
    # the station and the floor, found by role, replayed alone between their measured interfaces
    assert rep["locate"]["replay"]["mixing_station_alone"] and rep["locate"]["replay"]["emitter_alone"]
    assert set(rep["emitter_calibration"]["values"]) == {"floor.Q_nominal"}
    words = {m["mode"] for m in rep["locate"]["modes"]}
    assert any("heat pump on" in w for w in words) and not any("CHP" in w for w in words)
    skipped = {c["id"]: c.get("reason", "") for c in rep["candidates"] if not c.get("fitted")}
    assert "house2 has no chp" in skipped.get("idle_generator_flow", "")
    assert "heat_pump" in rep["energy"] and "chp" not in rep["energy"]


def test_a_house_file_written_for_the_test_is_diagnosed_on_its_own_recording(tmp_path):
    """house 4's plant with a smaller boiler under another name: the twin's own day of it,
    recorded every minute, is replayed through the derived cut and blamed on nothing."""
    path = tmp_path / "small_boiler.toml"
    path.write_text(f'[house]\nname = "small_boiler"\nbase = "{HOUSES / "house4.toml"}"\n[boiler]\nP_nom = 16000.0\n')
    house = load_house(path, start="2021-01-12")
    t, rows = house.run(86400.0, dt=1.0, out_interval=60.0)
    roles = roles_of(path)
    keep = list(roles.commands) + [s for s in ("boiler.T_sup", "boiler.T_ret", "boiler.m_flow", "boiler.Q_flow",
                                               "mixer.m_flow", "mixer.T_sup", "mixer.T_ret", "zone.T_room")]
    keep += [f"storage.T_sensor_{k}" for k in range(1, 11)]
    data = {s: rows[:, house.catalogue.index(s)] for s in keep}
    recording_io.write_csv(tmp_path / "rec.csv", t, data, tmp_path / "columns.toml", start="2021-01-12", house=path)
    rec = recording_io.load(tmp_path / "rec.csv", tmp_path / "columns.toml", house=path)
    rep = diagnose(rec, house=str(path), log=lambda *a: None, plots=False, jobs=1)
    assert rep["locate"]["replay"]["plant"] == "small_boiler_cut_circuit"
    assert rep["verdict"] == "no_missing_physics", (rep["verdict"], rep["locate"]["mismatched_signals"])
    assert np.isfinite(rep["energy"]["boiler"]["error_before_pct"])


def _house2_day(tmp_path, overrides: dict, days: float, signals: list):
    """The twin's own `days` of house 2 from 12 January with `overrides`, recorded every minute:
    the commands, the circuit, the draw, the storage sensors and `signals`."""
    house = load_house("house2", start="2021-01-12", overrides=overrides)
    t, rows = house.run(days * 86400.0, dt=1.0, out_interval=60.0)
    keep = list(roles_of("house2").commands) + signals + ["mixer.m_flow", "mixer.T_sup", "mixer.T_ret",
                                                          "dhw.m_flow_hot"]
    keep += [f"storage.T_sensor_{k}" for k in range(1, 11)]
    data = {s: rows[:, house.catalogue.index(s)] for s in keep}
    recording_io.write_csv(tmp_path / "rec.csv", t, data, tmp_path / "columns.toml", start="2021-01-12", house="house2")
    return recording_io.load(tmp_path / "rec.csv", tmp_path / "columns.toml", house="house2")


def test_a_heat_pump_that_lost_capacity_is_named_and_sized_on_house2(tmp_path):
    """The twin's own day of house 2 with the heat pump's heat and COP x 0.7 at the same pump
    flow (a line of a house file): the candidate bound to the heat-pump kind names it within 10 %,
    against its COP and defrost look-alikes and the storage loss."""
    from plant.diagnose.effects import catalogue

    f = 0.7
    ov = {"heat_pump.P_heat_nom": f * 5750.0, "heat_pump.COP_nom": f * 4.65, "heat_pump.dT": f * 5.0}
    rec = _house2_day(tmp_path, ov, 1.0, ["heat_pump.T_sup", "heat_pump.T_ret", "heat_pump.m_flow",
                                          "heat_pump.Q_flow", "heat_pump.P_el"])
    ids = ("heat_pump_capacity", "heat_pump_cop", "defrost_share", "heat_loss")
    rep = diagnose(rec, house="house2", log=lambda *a: None, plots=False, jobs=1,
                   effects=[e for e in catalogue("house2") if e.id in ids])
    assert rep["effect"] == "heat_pump_capacity" and rep["component"] == "heat_pump", (rep["verdict"], rep["effect"])
    # against the house file: the nominal re-fit may take up to 10 % of a capacity within the
    # unit's tolerance (P_heat_nom +-10 %), the candidate the rest
    assert abs(rep["size"]["factor_of_file"] / f - 1.0) < 0.10, (rep["size"], rep["nominal_refit"]["parameters"])
    assert rep["affected_heldout_rmse_after"] <= 0.5 * rep["affected_heldout_rmse_before"]


def test_a_floor_whose_screed_stores_less_is_named_and_sized_on_house2(tmp_path):
    """The twin's own two days of house 2 with the floor's screed x 0.4 (a line of a house file):
    behind the circuit cut the floor is replayed alone on the measured circuit and room, and the
    candidate bound to the floor-heating kind names it within 15 % against the return sensor's
    lag and delay."""
    from plant.diagnose.effects import catalogue

    f = 0.4
    rec = _house2_day(tmp_path, {"floor.C_screed": f * 2.7e7}, 2.0, ["heat_pump.T_sup", "heat_pump.T_ret",
                                                                      "heat_pump.m_flow", "heating.T_sup", "zone.T_room"])
    ids = ("slab_capacity", "sensor_lag", "transport_delay")
    # the twin's own plant: nothing for the nominal re-fit to take up
    rep = diagnose(rec, house="house2", log=lambda *a: None, plots=False, jobs=1, refit_nominal=False,
                   effects=[e for e in catalogue("house2") if e.id in ids])
    assert rep["effect"] == "slab_capacity" and rep["component"] == "floor", (rep["verdict"], rep["effect"])
    assert abs(rep["size"]["factor_of_file"] / f - 1.0) < 0.15, rep["size"]
    assert rep["affected_heldout_rmse_after"] <= 0.5 * rep["affected_heldout_rmse_before"]
