"""The diagnosis replays on a cut: measured boundaries instead of the twin's own load profiles;
stagnant-pipe sensors scored only while their branch flows; Guideline 14 figures; verdicts when
no candidate explains a mismatch."""
import math

import numpy as np

from plant.diagnose import cut, locate, replay, synth
from plant.diagnose.context import Context, stagnant_mask

CIRCUIT = synth.LAB_SIGNALS + ["dhw.m_flow_hot"]


def test_a_recording_with_the_circuit_and_the_draw_is_replayed_on_the_cut():
    # the twin's own recording, replayed on house1_cut_circuit: the heating circuit and the hot
    # water follow the recording, the storages and generators stay within the 60 s sampling
    # of the boundaries (a whole-house run recorded every minute)
    rec = synth.make("none", days=1.0, signals=CIRCUIT, noise=False)
    rp = replay.Replayer(rec)
    assert rp.plant_name == "house1_cut_circuit" and rp.circuit
    assert {"mixer.T_sup", "storage.T_sensor_5"} <= rp.simulated and "zone.T_room" not in rp.simulated
    rows = rp.run()
    ctx = Context.build(rec, train_days=0.4, simulated=rp.simulated)
    assert "zone.T_room" not in ctx.measured and "dhw.m_flow_hot" not in ctx.measured
    m = locate.metrics(ctx, rows[:, ctx.cols], ctx.train | ctx.held)
    for i in range(1, 11):
        assert m[f"storage.T_sensor_{i}"]["rmse"] < 0.6, (i, m[f"storage.T_sensor_{i}"])
    # the mixing station alone, between its measured interfaces, gives the supply after mixing
    assert m["mixer.T_sup"]["rmse"] < 0.6 and abs(m["mixer.T_sup"]["bias"]) < 0.1


def test_without_the_draw_the_whole_house_is_replayed():
    rec = synth.make("none", days=0.3, noise=False)
    rp = replay.Replayer(rec)
    assert rp.cut is None and rp.plant_name == "house1" and not rp.circuit
    assert "zone.T_room" in rp.simulated


def test_requirements_say_which_cut_each_signal_enables():
    req = replay.requirements()["measured boundaries (optional; what each signal enables)"]
    text = "\n".join(req)
    for s in cut.CUTS[0].bindings.values():
        assert f"{s} -> cut 'circuit'" in text
    assert "switch.T_sup -> the mixing station replayed alone" in text


def test_a_leaking_valve_shows_in_the_mixing_station_replayed_alone():
    # the mixing station alone with the recorded set-points and measured interfaces: a 20 %
    # seat leak lifts its closed-valve supply by 20 % of (header - return)
    rec = synth.make("none", days=0.5, signals=CIRCUIT, noise=False, base={"thermostat.T_sup_constant": 20.0})
    tight = cut.replay_circuit(rec, "house1", {}, len(rec.time))
    leaky = cut.replay_circuit(rec, "house1", {"mixer.leak": 0.2}, len(rec.time))
    closed = (leaky["mixer.y_valve"] < 0.2 + 1e-4) & (rec.data["mixer.m_flow_set"] > 0.005)
    assert closed.sum() > 100 and np.all(tight["mixer.y_valve"][closed] < 0.05)
    T_p, T_r = rec.data["switch.T_sup"][closed], rec.data["mixer.T_ret"][closed]
    assert abs(np.mean(leaky["mixer.T_sup"][closed] - (0.2 * T_p + 0.8 * T_r))) < 0.2
    assert np.mean(leaky["mixer.T_sup"][closed] - tight["mixer.T_sup"][closed]) > 0.15 * np.mean(T_p - T_r)


def test_stagnant_pipe_sensors_are_scored_only_while_their_branch_flows():
    rec = synth.make("none", days=0.3, noise=False)
    measured = ["chp.T_sup", "boiler.T_sup", "storage.T_sensor_5"]
    mask = stagnant_mask(rec, measured)
    chp_on = rec.data["chp.on"] > 0.5
    assert not mask[~chp_on, 0].any()                          # CHP off: its outlet is not scored
    assert mask[1:, 0][chp_on[1:] & chp_on[:-1]].all()
    boiler_flow = rec.data["boiler.m_flow"] > 1e-3              # a measured flow beats the command
    assert not mask[~boiler_flow, 1].any()
    assert mask[:, 2].all()                                    # a storage sensor is always scored


def test_guideline_14_hourly_figures_follow_their_formula():
    rec = synth.make("none", days=0.5, noise=False)
    ctx = Context.build(rec, train_days=0.2)
    j = ctx.measured.index("boiler.Q_flow")
    sim = np.where(np.isfinite(ctx.meas), ctx.meas, 0.0)
    sim[:, j] = ctx.meas[:, j] * 0.9 + 50.0
    g = locate.ashrae_hourly(ctx, sim, ctx.train | ctx.held)["boiler.Q_flow"]
    ok = (ctx.train | ctx.held) & ctx.ok[:, j]
    hour = np.floor((ctx.rec.time - ctx.rec.time[0]) / 3600.0).astype(int)
    hours = [h for h in np.unique(hour[ok]) if (hour[ok] == h).sum() >= 30]
    m = np.array([ctx.meas[ok & (hour == h), j].mean() for h in hours])
    e = np.array([(ctx.meas[ok & (hour == h), j] - sim[ok & (hour == h), j]).mean() for h in hours])
    n = len(hours)
    assert g["hours"] == n
    assert math.isclose(g["cvrmse_pct"], 100 * math.sqrt((e ** 2).sum() / (n - 1)) / m.mean(), rel_tol=1e-9)
    assert math.isclose(g["nmbe_pct"], 100 * e.sum() / ((n - 1) * m.mean()), rel_tol=1e-9)
