"""The heating circuit found by role and its emitter replayed alone (plant/diagnose/emitter.py):
any house's station, coupling point, emitter and zone from the links; a floor replayed by its
kind's kernel, energy kept; its rating calibrated back from a recorded return."""
from pathlib import Path
import numpy as np

from plant.diagnose import emitter
from plant.diagnose.recording_io import Samples
from plant.water import CP


def test_every_shipped_house_has_its_circuit_found_by_role():
    expected = {"house1": ("mixer", "switch", "radiator", "radiator", "zone"),
                "house2": ("mixer", "heating", "floor", "floor_heating", "zone"),
                "house3": ("mixer", "switch", "floor", "floor_heating", "zone")}
    for house, (station, point, em, kind, zone) in expected.items():
        c = emitter.of(house)
        assert (c.station, c.point, c.emitter, c.kind, c.zone) == (station, point, em, kind, zone)
    assert emitter.of("house2").station_inputs[2] == "heating.T_sup"


def test_a_house_file_with_other_names_has_its_circuit_found(tmp_path):
    # house 2 with its station, coupling point, floor and zone renamed: found by the links alone
    text = (Path(__file__).resolve().parents[2] / "plant" / "houses" / "house2.toml").read_text()
    for old, new in (("mixer", "hk_mix"), ("[floor]", "[estrich]"), ('emitter = "floor"', 'emitter = "estrich"'),
                     ("[heating]", "[hk_weiche]"), ("heating.", "hk_weiche."), ('"zone.', '"raum.'),
                     ('zone = "zone"', 'zone = "raum"'), ("[zone]", "[raum]")):
        text = text.replace(old, new)
    path = tmp_path / "house_renamed.toml"
    path.write_text(text)
    c = emitter.of(str(path))
    assert (c.station, c.point, c.emitter, c.kind, c.zone) == ("hk_mix", "hk_weiche", "estrich", "floor_heating", "raum")
    assert c.emitter_inputs == ("hk_mix.m_flow", "hk_mix.T_sup", "raum.T_room")


def _circuit_recording(days=2.0):
    """House 2's circuit signals: the pump off 22:00-06:00, a supply that follows a slow day
    cycle, the room between 19 and 21 degC."""
    t = np.arange(0.0, days * 86400.0, 60.0)
    hour = (t / 3600.0) % 24.0
    on = (hour >= 6.0) & (hour < 22.0)
    data = {"mixer.m_flow": np.where(on, 0.2, 0.0), "mixer.T_sup": 34.0 + 4.0 * np.sin(2 * np.pi * t / 86400.0),
            "zone.T_room": 20.0 + np.sin(2 * np.pi * t / 86400.0 + 1.0), "mixer.T_ret": np.full(t.size, 26.0)}
    return Samples("test", "2021-01-10", t, data)


def test_the_floor_alone_reaches_its_rating_and_follows_its_screed():
    # held at the nominal point (40 degC supply, 20 degC room, the nominal flow) the floor's return
    # settles at the nominal 30 degC: EN 1264's characteristic, whatever it started at
    rec = _circuit_recording(days=4.0)
    n = len(rec.time)
    Q_N = 13280.0
    rec.data.update({"mixer.m_flow": np.full(n, Q_N / (CP * 10.0)), "mixer.T_sup": np.full(n, 40.0),
                     "zone.T_room": np.full(n, 20.0)})
    y = emitter.replay(rec, "house2", {}, n)["mixer.T_ret"]
    assert y[0] == 26.0 and abs(y[-1] - 30.0) < 0.01, y[-1]
    # a smaller screed follows the supply's day cycle further: a larger swing of the return
    rec = _circuit_recording()
    n = len(rec.time)
    y = emitter.replay(rec, "house2", {}, n)["mixer.T_ret"]
    small = emitter.replay(rec, "house2", {"floor.C_screed": 0.3 * 2.7e7}, n)["mixer.T_ret"]
    assert np.all(np.isfinite(y)) and np.ptp(small[n // 2:]) > 1.2 * np.ptp(y[n // 2:])


def test_the_floor_alone_calibration_finds_its_rating():
    rec = _circuit_recording(days=1.5)
    n = len(rec.time)
    truth = {"floor.Q_nominal": 0.8 * 13280.0}
    rec.data["mixer.T_ret"] = emitter.replay(rec, "house2", truth, n)["mixer.T_ret"] \
        + np.random.default_rng(3).normal(0.0, 0.05, n)
    flow = rec.data["mixer.m_flow"] > 1e-3
    cal = emitter.calibrate(rec, "house2", flow & (rec.time < 86400.0))
    assert cal["elements"] == 1 and cal["rms_K"] < 0.07, cal
    assert abs(cal["values"]["floor.Q_nominal"] / truth["floor.Q_nominal"] - 1.0) < 0.03, cal
    assert not cal["at_bound"]


def test_a_radiator_not_calibrated_is_the_house_files_own_and_follows_the_twins_return():
    # a June day of the twin's house 1: the circuit flows at 15 samples, too few to calibrate the
    # radiator alone, which then runs the house file's kernel and values and reads the twin's own
    # return within 0.1 K (the twin steps at 1 s, the replay between 60 s samples). A chain of
    # 5 elements, what it ran before, cooled faster after the run and was 3 K off
    from plant.house import load_house

    h = load_house("house1", start="2021-06-15")
    times, rows = h.run(86400.0, dt=1.0, out_interval=60.0)
    c = emitter.of("house1")
    names = (*c.emitter_inputs, *c.emitter_outputs)
    rec = Samples("twin", "2021-06-15", times, {s: rows[:, h.catalogue.index(s)] for s in names})
    n = len(times)
    flowing = rec.data["mixer.m_flow"] > 1e-3
    assert 0 < flowing.sum() < 30
    own = emitter.replay(rec, "house1", {}, n)["mixer.T_ret"]
    chain = emitter.replay(rec, "house1", {}, n, 5)["mixer.T_ret"]
    assert np.abs(own - rec.data["mixer.T_ret"]).max() < 0.1
    assert np.abs(chain - rec.data["mixer.T_ret"]).max() > 2.0
