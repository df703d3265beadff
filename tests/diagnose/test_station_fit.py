"""A candidate on the mixing station replayed alone is fitted with the station calibrated again at
each of its values (station_fit.py): a rig recording whose PLC runs the circuit pump on with the
valve closed, where the station calibrated first takes part of the leak."""
from plant.diagnose import diagnose, recording_io
from plant.diagnose.effects import catalogue


def _leak(tmp_path, case, drop=None):
    from rigsim.suite import make_case

    make_case(case, tmp_path, days=2.0, start="2021-01-10", realisation=1)
    d = tmp_path / case
    columns = d / "columns.toml"
    if drop:  # the columns file a user wrote without this signal
        columns.write_text("\n".join(line for line in columns.read_text().splitlines()
                                     if f'signal = "{drop}"' not in line) + "\n")
    rec = recording_io.load(d, columns)
    rep = diagnose(rec, train_days=1.0, log=lambda *a: None, plots=False, jobs=1, refit_nominal=False,
                   effects=[e for e in catalogue() if e.id == "valve_leakage"])
    return next(c for c in rep["candidates"] if c["id"] == "valve_leakage")


def test_the_leak_is_fitted_with_the_station_calibrated_at_each_value(tmp_path):
    leak = _leak(tmp_path, "valve_leak_20")
    assert leak["plausible"] and "calibrated again at each value" in leak["fit_note"]
    assert set(leak["nominal_refit"]) == {"mixer.t_stroke", "mixer.K_i"}
    # 0.197 here; with the station calibrated once, before the candidate, 0.186
    assert abs(leak["parameters"]["leak"]["value"] - 0.20) < 0.05 * 0.20


def test_a_tight_valve_fits_no_leak(tmp_path):
    leak = _leak(tmp_path, "null_a")
    assert leak["parameters"]["leak"]["value"] < 0.02


def test_a_leak_without_the_recorded_set_point_says_what_to_map(tmp_path):
    """The supply set-point left out of the columns file is replayed from the measured supply:
    the replayed valve then never closes, and the reason says to map the set-point, not that the
    lab's valve never closed."""
    leak = _leak(tmp_path, "valve_leak_20", drop="mixer.T_sup_set")
    assert not leak["plausible"]
    assert "mixer.T_sup_set is not recorded (replayed from the measured mixer.T_sup)" in leak["reason"]
    assert "map the supply set-point" in leak["reason"]
