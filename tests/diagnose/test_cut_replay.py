"""The diagnosis replays on a cut: measured boundaries instead of the twin's own load profiles;
stagnant-pipe sensors modelled; the radiator alone as calibrated elements; the mixing station
alone calibrated; Guideline 14 figures;
verdicts when no candidate explains a mismatch."""
import math
import warnings

import numpy as np

from plant.diagnose import cut, emitter, locate, replay, requirements
from plant.truth import synth
from plant.diagnose import calibration, pipe_sensor
from plant.diagnose.context import Context
from plant.diagnose.pipe_sensor import scored_mask
from plant.diagnose.roles import of as roles_of

CIRCUIT = synth.LAB_SIGNALS + ["dhw.m_flow_hot"]
PIPES = roles_of("house1").pipes


def test_a_recording_with_the_circuit_and_the_draw_is_replayed_on_the_cut():
    # the twin's own recording, replayed on house1_cut_circuit: the heating circuit and the hot
    # water follow the recording, the storages and generators stay within the 60 s sampling
    # of the boundaries (a whole-house run recorded every minute)
    rec = synth.make("none", days=1.0, signals=CIRCUIT, noise=False)
    rp = replay.Replayer(rec)
    assert rp.plant_label == "house1_cut_circuit" and rp.circuit
    assert {"mixer.T_sup", "storage.T_sensor_5"} <= rp.simulated and "zone.T_room" not in rp.simulated
    rows = rp.run().rows
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
    req = requirements.requirements()["measured boundaries (optional; what each signal enables)"]
    text = "\n".join(req)
    for s in cut.circuit_cut("house1").bindings.values():
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


def test_pipe_sensors_are_scored_except_where_their_branch_switches():
    rec = synth.make("none", days=0.6, noise=False)
    measured = ["chp.T_sup", "boiler.T_sup", "storage.T_sensor_5"]
    mask = scored_mask(rec, measured, PIPES)
    # a measured flow beats the command: the recording has the boiler's flow, not the CHP's
    assert np.array_equal(pipe_sensor.recorded_flowing(rec, "boiler.T_sup", PIPES), rec.data["boiler.m_flow"] > 1e-3)
    assert np.array_equal(pipe_sensor.recorded_flowing(rec, "chp.T_sup", PIPES), rec.data["chp.on"] > 0.5)
    for j, s in enumerate(measured[:2]):
        f = pipe_sensor.recorded_flowing(rec, s, PIPES)
        switches = np.flatnonzero(f[1:] != f[:-1]) + 1
        assert switches.size >= 2 and not mask[switches, j].any()  # a start or stop: its instant is unknown
        assert mask[:, j].sum() == len(mask) - switches.size
    assert mask[:, 2].all()                                    # a storage sensor is always scored


class _Rec:
    """The part of a recording the pipe-sensor model reads: times and signals."""

    def __init__(self, time, data):
        self.time, self.data = time, data

    def has(self, s):
        return s in self.data


def _fit_chp_pipe(t, measured, fluid, flow, T_room):
    """The CHP supply sensor's modelled reading of `fluid` at `flow`, fitted to `measured` over
    the first half: -> (reading, PipeFit)."""
    out = np.column_stack([fluid, flow])
    fits = pipe_sensor.apply(_Rec(t, {"chp.T_sup": measured, "chp.m_flow": flow}), out,
                             {"chp.T_sup": 0, "chp.m_flow": 1}, t.size, T_room, t[-1] / 2, PIPES)
    return out[:, 0], fits["chp.m_flow"]


def test_a_stagnant_pipe_sensor_cools_toward_the_plant_room_and_tau_is_fitted():
    # the recorded reading of a stagnant pipe follows Newton cooling with tau = 1500 s; the
    # replay's reading is fitted on the training samples to that tau
    t = np.arange(0.0, 6 * 3600.0, 60.0)
    flowing = (t % 7200.0) < 2400.0
    fluid = np.full(t.size, 60.0)
    flow = np.where(flowing, 0.1, 0.0)
    truth = pipe_sensor.cooled(t, fluid, flow, pipe_sensor.PipeFit(1500.0, 0.1), 18.0)
    stop = np.flatnonzero(flowing[:-1] & ~flowing[1:])[0] + 1
    assert truth[stop - 1] == 60.0 and abs(truth[stop + 24] - (18.0 + 42.0 * np.exp(-1500.0 / 1500.0))) < 1e-9

    out, fit = _fit_chp_pipe(t, truth, fluid, flow, 18.0)
    assert abs(fit.tau / 1500.0 - 1.0) < 0.01 and not fit.fitted  # no trickle: no pipe water fitted
    assert np.max(np.abs(out - truth)) < 0.1 and np.all(out[flowing] == 60.0)


def test_a_trickle_renews_the_pipe_sensor_in_part_and_its_pipe_water_is_fitted():
    # each 6 h: the branch runs 2 h (0.1 kg/s of 60 degC), trickles 2 h (0.3 g/s of the 45 degC
    # return header: an idle flow) and stands 2 h; the sensor sits behind 50 g of pipe water
    t = np.arange(0.0, 12 * 3600.0, 60.0)
    phase = (t % 21600.0) // 7200.0
    flow = np.select([phase == 0, phase == 1], [0.1, 3e-4], 0.0)
    fluid = np.select([phase == 0, phase == 1], [60.0, 45.0], 70.0)   # a standing unit's fluid is stale
    truth = pipe_sensor.cooled(t, fluid, flow, pipe_sensor.PipeFit(1200.0, 0.05), 20.0)
    assert np.array_equal(truth[phase == 0][1:], fluid[phase == 0][1:])           # running: the fluid
    r, e = 3e-4 * 60.0 / 0.05, np.exp(-60.0 / 1200.0)                            # plug-flow steady state
    end = np.flatnonzero(phase == 1)[-1]
    assert abs(truth[end] - (20.0 + r * 25.0 / (1.0 - (1.0 - r) * e))) < 0.01   # 42.1 degC, far from the room
    stand = np.flatnonzero(phase == 2)
    assert abs(truth[stand[-1]] - (20.0 + (truth[stand[0] - 1] - 20.0) * np.exp(-7200.0 / 1200.0))) < 0.01
    # continuous in the flow: a flow of 1e-9 kg/s reads as a standing pipe does
    tiny = pipe_sensor.cooled(t, fluid, np.where(flow > 0.01, flow, np.where(flow > 0, 1e-9, 0.0)),
                              pipe_sensor.PipeFit(1200.0, 0.05), 20.0)
    still = pipe_sensor.cooled(t, fluid, np.where(flow > 0.01, flow, 0.0), pipe_sensor.PipeFit(1200.0, 0.05), 20.0)
    assert np.max(np.abs(tiny - still)) < 1e-3

    out, fit = _fit_chp_pipe(t, truth, fluid, flow, 20.0)
    assert fit.fitted and abs(fit.tau / 1200.0 - 1.0) < 0.02 and abs(fit.mass / 0.05 - 1.0) < 0.05
    assert np.max(np.abs(out - truth)) < 0.1


def test_the_plant_room_is_read_off_long_standstills_of_the_coolest_branch():
    # the CHP stands 8 h in a 23 degC room; the boiler stands as long but an unrecorded flow
    # keeps its pipe at 35 degC (it reads above the room, never below it): the room is 23 degC
    t = np.arange(0.0, 24 * 3600.0, 60.0)
    flowing = (t % (12 * 3600.0)) < 4 * 3600.0
    chp = pipe_sensor.cooled(t, np.full(t.size, 70.0), np.where(flowing, 0.1, 0.0), pipe_sensor.PipeFit(1500.0, 0.1),
                             23.0)

    rec = _Rec(t, {"chp.T_sup": chp, "chp.m_flow": np.where(flowing, 0.1, 0.0),
                   "boiler.T_sup": np.where(flowing, 70.0, 35.0), "boiler.m_flow": np.where(flowing, 0.2, 0.0)})
    assert abs(pipe_sensor.plant_room(rec, PIPES) - 23.0) < 0.01
    rec.data["chp.m_flow"] = rec.data["boiler.m_flow"] = np.full(t.size, 0.1)  # nothing stands 6 h
    assert pipe_sensor.plant_room(rec, PIPES) is None


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


def test_the_weighted_residuals_square_to_the_cost():
    # the identifiability's Gauss-Newton Jacobian is taken of these: their sum of squares must be
    # the cost the calibration minimises, unscored samples and an unscored signal included
    rec = synth.make("none", days=0.5, noise=False)
    ctx = Context.build(rec, train_days=0.2)
    rng = np.random.default_rng(3)
    sim = np.where(np.isfinite(ctx.meas), ctx.meas, 0.0) + rng.normal(0.0, 0.5, ctx.meas.shape)
    sim[::7, 2] = np.nan
    sim[:, ctx.measured.index("boiler.Q_flow")] = np.nan
    r = ctx.weighted_residuals(sim, ctx.train)
    assert r.shape == (int(ctx.train.sum()) * len(ctx.measured),) and np.isfinite(r).all()
    with warnings.catch_warnings():  # the unscored signal's mean square is a mean of nothing: NaN, skipped
        warnings.filterwarnings("ignore", "Mean of empty slice", RuntimeWarning)
        cost = ctx.cost(sim, ctx.train)
    assert math.isclose(float(r @ r), cost, rel_tol=1e-12)


def test_a_radiator_chain_of_any_length_gives_its_rating_at_the_nominal_point():
    # EN 442 nominal point 60/45/21 degC: in steady state at the nominal flow the chain returns
    # 45 degC and emits Q_N, whatever its element count (the element coefficient is solved for it)
    Q_N, cp = 8778.0, 4180.0
    m = Q_N / (cp * 15.0)
    t = np.arange(0.0, 6 * 3600.0 + 1, 60.0)
    for N in (1, 3, 5):
        k = emitter._element_coefficient(Q_N, 60.0, 45.0, 21.0, 1.3, N)
        x = np.full(N, 30.0)
        out = np.empty(t.size)
        emitter._radiator_run(t, np.full(t.size, m), np.full(t.size, 60.0), np.full(t.size, 21.0), x, k, 1.3,
                          cp * 1000.0 * 0.12 / N, out)
        assert abs(out[-1] - 45.0) < 0.01, (N, out[-1])
        assert abs(m * cp * (60.0 - out[-1]) / Q_N - 1.0) < 1e-3
        emitted = sum(k * (T - 21.0) ** 1.3 for T in x)   # the elements' emission balances the flow's heat
        assert abs(emitted / Q_N - 1.0) < 1e-3


def test_the_radiator_alone_calibration_finds_elements_rating_and_water():
    rec = synth.make("none", days=1.5, signals=CIRCUIT, noise=False)
    truth = {"radiator.Q_nominal": 7000.0, "radiator.V_water": 0.12}
    rec.data["mixer.T_ret"] = emitter.replay(rec, "house1", truth, len(rec.time), 3)["mixer.T_ret"] \
        + np.random.default_rng(1).normal(0.0, 0.05, len(rec.time))
    flow = rec.data["mixer.m_flow"] > 1e-3
    cal = emitter.calibrate(rec, "house1", flow & (rec.time < rec.time[0] + 86400.0))
    assert cal["elements"] == 3 and cal["rms_K"] < 0.06
    assert abs(cal["values"]["radiator.Q_nominal"] / 7000.0 - 1.0) < 0.02
    assert abs(cal["values"]["radiator.V_water"] / 0.12 - 1.0) < 0.05
    assert cal["identifiability"]["identifiable"] and not cal["at_bound"]


def test_the_mixing_station_alone_calibration_finds_its_actuator_and_gain():
    # a slower actuator and a stronger integrator than the file's (120 s, 2e-4 1/(K s)): the
    # supply after mixing, recorded with 0.05 K noise, gives both back
    rec = synth.make("none", days=1.5, signals=CIRCUIT, noise=False)
    truth = {"mixer.t_stroke": 240.0, "mixer.K_i": 1e-3}
    rec.data["mixer.T_sup"] = cut.replay_circuit(rec, "house1", truth, len(rec.time))["mixer.T_sup"] \
        + np.random.default_rng(2).normal(0.0, 0.05, len(rec.time))
    flow = rec.data["mixer.m_flow"] > 1e-3
    cal = cut.calibrate_mixer(rec, "house1", flow & (rec.time < rec.time[0] + 86400.0))
    assert cal["rms_K"] < 0.06 < 0.5 < cal["rms_file_K"], cal
    for q, v in truth.items():
        assert abs(cal["values"][q] / v - 1.0) < 0.2, cal
    assert not cal["at_bound"]


def test_a_circuit_that_never_flows_in_training_keeps_the_file_model_and_values_and_says_why():
    rec = synth.make("none", days=0.5, signals=CIRCUIT, noise=False)
    rec.data["mixer.m_flow"] = np.zeros(len(rec.time))
    rp = replay.Replayer(rec)
    assert rp.circuit and rp.emitter
    train = rec.time < rec.time[0] + 0.2 * 86400.0
    for cal in (rp.calibrate_emitter(train), rp.calibrate_mixer(train)):
        assert cal["calibrated"] is False and "flows at 0 recorded samples" in cal["why"], cal
    assert not rp.base and not rp.calibrated and rp.emitter_elements == emitter.OWN  # the house file's radiator
    assert sum("not calibrated" in n for n in rp.notes) == 2


def test_identifiability_names_a_flat_parameter_and_a_trade_off():
    # residuals (a + b - 1, 0.1 (a - 0.5), 0.1): a and b trade off; (a - 0.3, 3e-5 c, 0.1): c is flat
    trade = calibration.identifiability(lambda v: [v[0] + v[1] - 1.0, 0.1 * (v[0] - 0.5), 0.1],
                                        ["a", "b"], [0, 0], [1, 1], [0.5, 0.5], 100.0)
    assert not trade["identifiable"] and "trade off" in trade["why"] and trade["correlations"]["a|b"] < -0.95
    flat = calibration.identifiability(lambda v: [v[0] - 0.3, math.sqrt(1e-9) * v[1], 0.1],
                                       ["a", "c"], [0, 0], [1, 1], [0.3, 0.5], 100.0)
    assert [p["identifiable"] for p in flat["parameters"]] == [True, False] and "c:" in flat["why"]
    sharp = calibration.identifiability(lambda v: [v[0] - 0.3, v[1] - 0.6, 0.1],
                                        ["a", "b"], [0, 0], [1, 1], [0.3, 0.6], 100.0)
    assert sharp["identifiable"] and sharp["why"] == ""
