"""Bad input is repaired with a warning or rejected with a clear message."""
from pathlib import Path

import numpy as np
import pytest

from plant.catalogue import CATALOGUE
from plant.diagnose import recording_io, requirements
from plant.truth import synth
from plant.errors import ConfigError, DataError


@pytest.fixture(scope="module")
def rec():
    return synth.make("none", days=0.25, noise=False)


def _write(tmp_path, rec, mutate=None, units=None, extra=None):
    data = dict(rec.data)
    t = rec.time.copy()
    if extra:
        data.update(extra)
    csv = tmp_path / "lab.csv"
    m = tmp_path / "columns.toml"
    recording_io.write_csv(csv, t, data, m, start=rec.start, units=units)
    if mutate:
        lines = csv.read_text().splitlines()
        csv.write_text("\n".join(mutate(lines)) + "\n")
    return csv, m


def test_round_trip(tmp_path, rec):
    csv, m = _write(tmp_path, rec)
    r = recording_io.load(csv, m)
    assert r.start == rec.start and not r.warnings
    assert np.allclose(r.data["chp.T_sup"], rec.data["chp.T_sup"], atol=1e-3)


def test_unsorted_duplicate_gap_repaired(tmp_path, rec):
    def mutate(lines):
        body = lines[1:]
        body[10], body[11] = body[11], body[10]          # unsorted
        body.insert(20, body[20])                        # duplicate
        del body[100:130]                                # a 30-min gap
        return [lines[0]] + body
    csv, m = _write(tmp_path, rec, mutate)
    r = recording_io.load(csv, m)
    text = " ".join(r.warnings)
    assert "sorted" in text and "duplicate" in text and "gap" in text
    assert np.all(np.diff(r.time) > 0)
    assert not r.valid.all()


def test_unknown_column_ignored_and_kelvin_converted(tmp_path, rec):
    csv, m = _write(tmp_path, rec, units={"chp.T_sup": "K"},
                    extra={"chp.T_sup": rec.data["chp.T_sup"] + 273.15})
    with open(csv) as fh:
        header = fh.readline().strip()
    csv.write_text(csv.read_text().replace(header, header + ",junk", 1).replace("\n", ",1\n")
                   .replace(header + ",junk,1", header + ",junk"))
    r = recording_io.load(csv, m)
    assert any("not in the mapping" in w for w in r.warnings)
    assert abs(np.median(r.data["chp.T_sup"]) - np.median(rec.data["chp.T_sup"])) < 0.01


def test_kelvin_labelled_celsius_rejected(tmp_path, rec):
    csv, m = _write(tmp_path, rec, extra={"chp.T_sup": rec.data["chp.T_sup"] + 273.15})
    with pytest.raises(DataError, match="looks like Kelvin"):
        recording_io.load(csv, m)


def test_unknown_unit_and_wrong_unit_rejected(tmp_path, rec):
    csv, m = _write(tmp_path, rec, units={"chp.T_sup": "furlongs"})
    with pytest.raises(ConfigError, match="unknown unit"):
        recording_io.load(csv, m)
    csv, m = _write(tmp_path, rec, units={"chp.T_sup": "kW"})
    with pytest.raises(ConfigError, match="wrong unit"):
        recording_io.load(csv, m)


def test_missing_command_rejected_with_requirements(tmp_path, rec):
    data = {k: v for k, v in rec.data.items() if k != "boiler.U_set"}
    r = recording_io.Samples("x", rec.start, rec.time, data, [], None, {})
    with pytest.raises(ConfigError, match="boiler.U_set") as exc:
        requirements.check(r)
    assert "must contain" in str(exc.value)


def test_requirements_cli(capsys):
    from cli.main import main

    assert main(["diagnose", "--requirements", "house1"]) == 0
    out = capsys.readouterr().out
    assert "chp.on" in out and "storage.T_sensor_10" in out


def test_a_recording_of_another_house_is_refused_naming_the_fix(tmp_path, rec, capsys):
    # a house-1 recording given with house 2's file (air-source heat pump, floor heating, no
    # CHP): its columns are read against house 2's catalogue; the error says so and names the fix
    from cli.main import main
    from plant.diagnose import diagnose

    csv, m = _write(tmp_path, rec)
    assert main(["diagnose", "--house", "house2", "--recording", str(csv), "--map", str(m)]) != 0
    err = capsys.readouterr().err
    assert "name instances house2 does not have (chp, dhw_pump, dhw_storage): a recording of another house?" in err
    assert "(--house)" in err and "twin signals house2" in err and "'chp.T_sup' = 'chp.T_sup': unknown signal" in err
    # what a recording of house 3 must hold is said from its own roles and derived cut
    assert main(["diagnose", "--requirements", "house3"]) == 0
    out = capsys.readouterr().out
    assert "heat_pump.on" in out and "solar.upper" in out and "chp.on" not in out
    assert "ground source: ground.T_ground" in out and "heating circuit: mixer.T_sup" in out
    assert "all of mixer.m_flow, mixer.T_sup, mixer.T_ret, dhw.m_flow_hot (replaces mixer, floor, zone" in out
    # the same recording, already read, given to the diagnosis with house 5's file
    with pytest.raises(ConfigError, match="holds signals house5 does not have: dhw_pump.on.*a recording of another house"):
        diagnose(rec, house="house5")


def test_a_house_file_that_keeps_house_1s_instances_is_diagnosed(tmp_path):
    # a lab's own copy of house 1 with another storage size and CHP: the same plant, accepted
    from plant.house import load_spec

    text = Path(load_spec("house1").path).read_text()
    assert "P_el_max = 1900.0" in text and "volume = 0.8\n" in text
    own = tmp_path / "our_house.toml"
    own.write_text(text.replace("P_el_max = 1900.0", "P_el_max = 2500.0").replace("volume = 0.8\n", "volume = 1.0\n"))
    requirements.check_house(own)
    spec = load_spec(own)
    assert spec.instances["storage"].params.volume == 1.0 and spec.instances["chp"].params.P_el_max == 2500.0


def test_gateway_recording_directory_is_diagnosed(tmp_path):
    # a gateway run (built-in rules, lock-step, recorder every 60 s) read back without a mapping
    # file: its columns are catalogue names; the twin replaying its own run finds nothing missing
    from gateway.clock import LockStepClock
    from gateway.runtime import Runtime
    from plant.diagnose import diagnose
    from plant.diagnose.effects import catalogue
    from plant.house import load_house

    run = tmp_path / "run"
    rt = Runtime(load_house("house1", start="2021-01-12"), clock=LockStepClock(1.0), record=run,
                 record_interval=60.0)
    for _ in range(12 * 3600):
        rt.tick(1.0)
    rt.stop()
    rec = recording_io.load(run)
    assert rec.start == "2021-01-12"
    assert rec.has("chp.on") and rec.has("storage.T_sensor_10") and rec.has("chp.Q_flow_meter")
    rep = diagnose(rec, train_days=0.2, log=lambda *a: None, plots=False, refit_nominal=False,
                   effects=[e for e in catalogue() if e.id in ("heat_loss", "sensor_offset")])
    assert rep["verdict"] == "no_missing_physics", rep["finding"]
    # the replay switches commands between 60 s samples and steps at 5 s: close, not identical
    for i in range(1, 11):
        assert rep["signals"][f"storage.T_sensor_{i}"]["heldout_rmse_before"] < 0.5


def test_columns_map_percent_onto_volts_scale_offset_and_sensor_heights(tmp_path, rec):
    """A boiler command logged in % (range map 0-100 % -> 0-10 V), a temperature logged with a
    scale and offset, and storage sensors at the lab's own heights."""
    U = rec.data["boiler.U_set"]
    extra = {"boiler.U_set": U * 10.0, "chp.T_sup": (rec.data["chp.T_sup"] - 1.0) / 2.0}
    csv, m = _write(tmp_path, rec, extra=extra)
    text = m.read_text()
    text = text.replace('"boiler.U_set" = "boiler.U_set"', '"boiler.U_set" = { signal = "boiler.U_set", range = [0, 100, 0, 10] }')
    text = text.replace('"chp.T_sup" = "chp.T_sup"', '"chp.T_sup" = { signal = "chp.T_sup", unit = "degC", scale = 2.0, offset = 1.0 }')
    text = text.replace('"storage.T_sensor_10" = "storage.T_sensor_10"',
                        '"storage.T_sensor_10" = { signal = "storage.T_sensor_10", height = 0.97 }')
    text = "\n".join(l for l in text.splitlines() if not l.startswith(('"boiler.U_set" = "V"', '"chp.T_sup" = "degC"')))
    m.write_text(text + "\n")
    r = recording_io.load(csv, m)
    assert np.allclose(r.data["boiler.U_set"], U, atol=1e-6)
    assert np.allclose(r.data["chp.T_sup"], rec.data["chp.T_sup"], atol=1e-3)
    ov = r.sensor_overrides()
    assert ov["storage.sensor_heights"][9] == 0.97 and ov["storage.sensor_heights"][0] == 0.05
    from plant.house import load_house

    house = load_house("house1", overrides=ov)  # the twin's sensor 10 sits where the lab's does
    top = house.state("storage")
    # at 0.97 of 1.63 m in 40 layers: 0.7 of the way from layer 0's centre to layer 1's
    assert house.get("storage.T_sensor_10") == pytest.approx(top[0] * 0.3 + top[1] * 0.7, abs=1e-9)


@pytest.mark.parametrize("entry, needle", [
    ('{ signal = "storage.T_sensor_1", height = 1.5 }', "height = 1.5: outside 0 … 1"),
    ('{ signal = "storage.T_sensor_1", range = [0, 0, 0, 10] }', "range = [0, 0, 0, 10]: must be [a, b, c, d] with a != b"),
    ('{ signal = "storage.T_sensor_1", scael = 2.0 }', "scael: unknown key; did you mean scale"),
    ('{ signal = "storage.T_sensor_1", range = [0, 100, 0, 10], unit = "K" }', "range maps straight onto the signal's unit"),
    ('{ signal = "storage.T_sensr_1" }', "unknown signal; did you mean storage.T_sensor_1"),
])
def test_bad_column_entries_are_named(tmp_path, rec, entry, needle):
    csv, m = _write(tmp_path, rec)
    text = m.read_text().replace('"storage.T_sensor_1" = "storage.T_sensor_1"', f'"storage.T_sensor_1" = {entry}')
    m.write_text(text)
    with pytest.raises(ConfigError) as exc:
        recording_io.load(csv, m)
    assert needle in str(exc.value) and str(m) in str(exc.value)


def test_declared_port_heights_move_the_twins_ports(tmp_path, rec):
    """[ports] storage = { top, bottom } (relative, as the lab's datasheet gives them) puts the
    coupling point's storage ports there in every replay: the surplus then enters below the
    top layers, which only warm by buoyancy, and the top sensor reads otherwise."""
    from plant.diagnose.replay import Replayer

    csv, m = _write(tmp_path, rec)
    plain = Replayer(recording_io.load(csv, m))
    m.write_text(m.read_text() + "\n[ports]\nstorage = { top = 0.9, bottom = 0.1 }\n")
    r = recording_io.load(csv, m)
    assert r.ports == {"storage": {"top": 0.9, "bottom": 0.1}}
    rp = Replayer(r)
    assert rp.lab["switch.storage_top"] == pytest.approx(0.9 * 1.63)
    assert rp.lab["switch.storage_bottom"] == pytest.approx(0.1 * 1.63)
    assert any("ports at 1.467 m and 0.163 m" in n and "house file: 1.6 m and 0.03 m" in n for n in rp.notes)
    until = 6 * 3600.0
    top = CATALOGUE.index("storage.T_sensor_10")
    a, b = plain.run(until=until).rows[:, top], rp.run(until=until).rows[:, top]
    assert np.nanmax(np.abs(a - b)) > 0.5


@pytest.mark.parametrize("table, needle", [
    ("storage = { top = 1.2, bottom = 0.1 }", "[ports] storage top = 1.2: outside 0 … 1"),
    ("storage = { top = 0.1, bottom = 0.9 }", "top = 0.1 must lie above bottom = 0.9"),
    ("storage = { upper = 0.9, bottom = 0.1 }", "expected { top = ..., bottom = ... }"),
    ("storag = { top = 0.9, bottom = 0.1 }", "[ports] storag: not a storage of the twin; did you mean storage"),
])
def test_bad_port_heights_are_named(tmp_path, rec, table, needle):
    csv, m = _write(tmp_path, rec)
    m.write_text(m.read_text() + f"\n[ports]\n{table}\n")
    with pytest.raises(ConfigError) as exc:
        recording_io.load(csv, m)
    assert needle in str(exc.value) and str(m) in str(exc.value)


def test_ports_of_a_storage_without_a_coupling_point_are_refused(tmp_path, rec):
    from plant.diagnose.replay import Replayer

    csv, m = _write(tmp_path, rec)
    m.write_text(m.read_text() + "\n[ports]\ndhw_storage = { top = 0.9, bottom = 0.1 }\n")
    with pytest.raises(ConfigError, match=r"\[ports\] dhw_storage: house1\S* has no coupling point whose "
                                          r"storage is 'dhw_storage'; ports can be declared for storage"):
        Replayer(recording_io.load(csv, m))


def test_a_recording_too_short_for_a_held_out_window_says_so():
    from plant.diagnose import diagnose

    short = synth.make("none", days=0.2, noise=False)  # 4.8 h: no room for 1 + 2 + 3 h
    with pytest.raises(DataError, match=r"spans 4\.8 h: too short for a training and a held-out window"):
        diagnose(short, train_days=0.1, log=lambda *a: None, plots=False)


def test_the_shipped_recording_with_date_time_stamps_reads_as_with_seconds(tmp_path):
    """The same lab export with its time column as local date-times under another name gives the
    same samples (the stamps' start is the mapping's), and an unreadable stamp drops its row
    with a warning."""
    from datetime import datetime, timedelta

    src = Path(__file__).resolve().parents[2] / "profiles" / "recordings" / "concealed_idle_flow"
    lines = (src / "recording.csv").read_text().splitlines()
    t0 = datetime(2021, 1, 10)
    out = ["Stamp" + lines[0][len("time"):]]
    for k, line in enumerate(lines[1:]):
        t, rest = line.split(",", 1)
        stamp = (t0 + timedelta(seconds=float(t))).isoformat(sep=" ", timespec="milliseconds")
        out.append(f"{'not a time' if k == 5 else stamp},{rest}")
    (tmp_path / "recording.csv").write_text("\n".join(out) + "\n")
    cols = (src / "columns.toml").read_text().replace('file = "recording.csv"', 'file = "recording.csv"\ntime = "Stamp"')
    (tmp_path / "columns.toml").write_text(cols)
    a = recording_io.load(src, src / "columns.toml")
    b = recording_io.load(tmp_path, tmp_path / "columns.toml")
    assert b.start == a.start == "2021-01-10"
    assert any("1 row(s) without a valid time dropped" in w for w in b.warnings)
    keep = np.ones(len(a.time), bool)
    keep[5] = False
    np.testing.assert_allclose(b.time, a.time[keep], atol=1e-3)
    for s in a.data:
        np.testing.assert_array_equal(b.data[s], a.data[s][keep])


def test_storage_sensors_the_twin_cannot_place_are_refused(tmp_path, rec):
    """Heights that do not rise with the sensor number: the twin numbers a storage's sensors from
    the bottom, so a lab's columns mapped out of order cannot be placed (named, with the fix)."""
    import re

    csv, m = _write(tmp_path, rec)
    text = m.read_text()
    for k, h in ((3, 0.40), (4, 0.30)):  # sensor 4 declared below sensor 3
        text = re.sub(rf'^("storage\.T_sensor_{k}") = "storage\.T_sensor_{k}"$',
                      rf'\1 = {{ signal = "storage.T_sensor_{k}", height = {h} }}', text, flags=re.M)
    assert "height = 0.3" in text
    m.write_text(text)
    with pytest.raises(ConfigError) as exc:
        recording_io.load(csv, m)
    msg = str(exc.value)
    assert str(m) in msg and "storage.T_sensor_4 at height 0.3 is not above" in msg
    assert "in the order of their heights" in msg


def test_a_recording_that_allows_no_cut_is_refused_when_a_cut_is_required(tmp_path, rec):
    from plant.diagnose.replay import Replayer

    keep = {k: v for k, v in rec.data.items() if k not in ("mixer.m_flow", "dhw.m_flow_hot")}
    csv, m = _write(tmp_path, type(rec)(rec.source, rec.start, rec.time, keep))
    r = recording_io.load(csv, m)
    assert Replayer(r).cut is None  # by default: the whole house, on the twin's profiles
    with pytest.raises(ConfigError) as exc:
        Replayer(r, require_cut=True)
    msg = str(exc.value)
    assert "maps no boundary a cut can use" in msg and "missing: mixer.m_flow" in msg and "dhw.m_flow_hot" in msg
    assert "twin diagnose --requirements house1" in msg


def test_a_recording_of_house2_is_read_against_house2s_catalogue(tmp_path):
    """The columns file names house 2's signals (from `twin signals house2`): read in its units;
    a house-1 signal in it is unknown to house 2, and the fix names house 2's list."""
    t = np.arange(0.0, 6 * 3600.0, 60.0)
    csv = tmp_path / "sf2.csv"
    csv.write_text("time,HP_TVL,VALVE,HC_FLOW\n" + "\n".join(f"{x},{40 + x / 3600:.3f},1,12.0" for x in t) + "\n")
    m = tmp_path / "columns.toml"
    m.write_text('[recording]\nstart = "2021-01-10"\n[columns]\nHP_TVL = "heat_pump.T_sup"\nVALVE = "hp_valve.upper"\n'
                 'HC_FLOW = "mixer.m_flow"\n[units]\nHC_FLOW = "l/min"\n')
    r = recording_io.load(csv, m, house="house2")
    assert r.has("heat_pump.T_sup") and r.has("hp_valve.upper")
    assert abs(r.data["mixer.m_flow"][0] - 0.2) < 0.01  # 12 l/min of water
    m.write_text(m.read_text().replace('VALVE = "hp_valve.upper"', 'VALVE = "chp.on"'))
    with pytest.raises(ConfigError) as e:
        recording_io.load(csv, m, house="house2")
    assert "'chp.on': unknown signal" in str(e.value) and "twin signals house2" in str(e.value)


def test_a_recording_without_a_date_starts_where_its_outdoor_air_matches_the_weather_profile(tmp_path):
    """`twin simulate --out` writes seconds, not dates: the day whose profile air the recorded air
    matches is taken (and said); air that matches no day keeps the house file's start (and says so)."""
    from profiles.loaders import start_offset, weather

    t = np.arange(60.0, 2 * 86400.0, 60.0)
    air = weather()["T_air"].at(start_offset("2021-06-15") + t)
    for name, T, start, said in (("june", air + 0.1, "2021-06-15", "matches the weather profile from 2021-06-15"),
                                 ("hot", np.full(t.size, 50.0), "2021-01-10", "assumed the house file's start 2021-01-10")):
        csv = tmp_path / f"{name}.csv"
        csv.write_text("time,weather.T_air,chp.T_sup\n" + "\n".join(f"{x},{y:.3f},60.0" for x, y in zip(t, T)) + "\n")
        r = recording_io.load(csv)
        assert r.start == start
        assert any(said in w and "no start date" in w for w in r.warnings), r.warnings


@pytest.mark.parametrize("days", ["0", "-1", "nan"])
def test_a_training_window_of_no_days_is_refused_naming_the_fix(tmp_path, rec, capsys, days):
    from cli.main import main

    csv, m = _write(tmp_path, rec)
    assert main(["diagnose", "--recording", str(csv), "--map", str(m), "--train-days", days]) != 0
    err = capsys.readouterr().err
    assert f"--train-days {float(days):g}: the training window needs more than 0 days (default 2" in err
