"""A sensor offset is the same in every operating state (effects/sensor.py SensorOffset.unlike):
a tank that stratifies differently around a sensor in some states only is not an offset."""
import dataclasses

import numpy as np
import pytest

from plant.diagnose import fit, verdict
from plant.truth import synth
from plant.diagnose.context import Context
from plant.diagnose.effects import catalogue
from plant.diagnose.effects.sensor import CONSTANT_SHARE, STATE_SHARE

OFFSET = next(e for e in catalogue() if e.id == "sensor_offset")


def _states(n, on_share):
    on = np.zeros(n, dtype=bool)
    on[: int(on_share * n)] = True
    return {"boiler_on": on, "chp_on": np.ones(n, dtype=bool)}


def test_a_constant_offset_with_noise_is_alike_in_every_state():
    rng = np.random.default_rng(3)
    e = 1.5 + 0.5 * rng.standard_normal(2000)
    assert OFFSET.unlike([float(np.mean(e))], e, _states(2000, 0.2)) == ""


def test_a_residual_missing_in_one_state_is_not_an_offset():
    n = 2000
    st = _states(n, 0.2)
    e = np.where(st["boiler_on"], 0.0, -1.6)   # the "offset" vanishes while the boiler runs
    why = OFFSET.unlike([float(np.mean(e))], e, st)
    assert why.startswith("not constant: with boiler on the residual keeps 0.00 of the -1.28 K offset")
    # an opposite sign in a state is no offset either
    e2 = np.where(st["boiler_on"], 0.5, -1.6)
    assert "boiler on" in OFFSET.unlike([float(np.mean(e2))], e2, st)
    # at half the offset it still is one (CONSTANT_SHARE), and a state under STATE_SHARE is not judged
    e3 = np.where(st["boiler_on"], -0.9, -1.6)
    assert CONSTANT_SHARE <= 0.9 / np.mean(-e3) and OFFSET.unlike([float(np.mean(e3))], e3, st) == ""
    rare = _states(n, 0.5 * STATE_SHARE)
    e4 = np.where(rare["boiler_on"], 0.0, -1.6)
    assert OFFSET.unlike([float(np.mean(e4))], e4, rare) == ""


def test_an_offset_that_is_not_constant_is_rejected_with_that_reason():
    """fit_signal passes over a storage sensor whose residual has not the offset's shape; fitted on
    that sensor alone it records the shape check (Result.local['unlike']), and the verdict rejects
    the candidate with it though it removes most of the sensor's own residual."""
    rec = synth.make("none", days=1.0, noise=False)
    ctx = Context.build(rec, train_days=0.5)
    sim = np.where(np.isfinite(ctx.meas), ctx.meas, 0.0)
    j = ctx.measured.index("storage.T_sensor_5")
    state = ctx.flags["heating_on"]
    assert STATE_SHARE < state[ctx.train].mean() < 1.0 - STATE_SHARE
    sim[:, j] -= np.where(state, 0.0, 2.0)      # reads 2 K high only while the heating is off
    assert fit.fit_signal(OFFSET, ctx, sim).signal != "storage.T_sensor_5"
    r = fit.fit_signal(OFFSET, ctx, sim, only="storage.T_sensor_5")
    assert r.signal == "storage.T_sensor_5"
    assert r.local["unlike"].startswith("not constant: with ")  # the first state where it is not
    judged = verdict._judged_local(r, n_eff=100.0)
    assert not judged.accepted and "not constant" in judged.reason
    # the same sensor reading 2 K high throughout is an offset, and named
    sim[:, j] = np.where(np.isfinite(ctx.meas[:, j]), ctx.meas[:, j], 0.0) - 2.0
    r = fit.fit_signal(OFFSET, ctx, sim)
    assert r.local["unlike"] == "" and r.theta[0] == pytest.approx(2.0, abs=1e-6)
    assert verdict._judged_local(r, n_eff=100.0).accepted


@pytest.mark.parametrize("gain, accepted", [(0.60, True), (0.40, False)])
def test_a_lag_within_its_sensors_limit_counts_where_it_removes_half_of_the_residual(gain, accepted):
    """A lag's residual is the rate of change times its time constant: small where the tank
    changes slowly. Within the sensor's limit it is the sensor's own only where it removes
    SHAPED_GAIN of the residual; an offset within the limit never is."""
    from plant.diagnose.effects.sensor import SensorLag

    lag = next(e for e in catalogue("house2") if e.id == "sensor_lag")
    before = 0.57
    local = {"heldout_rms_before": before, "heldout_rms_after": before * (1 - gain) ** 0.5, "gain": gain,
             "limit": 0.62, "neighbours": ["storage.T_sensor_8", "storage.T_sensor_10"]}
    r = fit.Result("sensor_lag", "sensor", "signal", True, theta=[600.0], signal="storage.T_sensor_9",
                   effect=lag, local=local)
    got = verdict._judged_local(r, n_eff=100.0)
    assert SensorLag.SHAPED_GAIN == 0.5 and got.accepted is accepted, got.reason
    if not accepted:
        assert "no sensor-own mismatch" in got.reason
    off = verdict._judged_local(fit.Result("sensor_offset", "sensor", "signal", True, theta=[0.5],
                                           signal="storage.T_sensor_9", effect=OFFSET, local=local), n_eff=100.0)
    assert not off.accepted and "no sensor-own mismatch" in off.reason


@pytest.mark.parametrize("effect, theta, accepted", [("sensor_lag", 87.0, False), ("sensor_lag", 95.0, True),
                                                     ("transport_delay", 90.0, False),
                                                     ("transport_delay", 180.0, True)])
def test_a_lag_or_dead_time_a_sleeve_gives_is_not_named(effect, theta, accepted):
    """A lag or dead time of at most OWN_LAG_S (a PT100 in its sleeve or thermowell, the rig
    descriptions' 20 ... 90 s) is the sensor's mounting, rejected with that reason however much of
    the sensor's residual it removes; beyond it the same fit is accepted. Both where judged on the
    sensor's own residual (a tank sensor) and where judged on the whole cost (a pipe sensor)."""
    from plant.diagnose.effects.sensor import OWN_LAG_S

    e = next(c for c in catalogue() if c.id == effect)
    local = {"heldout_rms_before": 1.32, "heldout_rms_after": 0.58, "gain": 0.81, "limit": 0.62,
             "neighbours": ["storage.T_sensor_2"]}
    r = fit.Result(effect, "sensor", "signal", True, theta=[theta], signal="storage.T_sensor_1", effect=e,
                   local=local)
    got = verdict._judged_local(r, n_eff=100.0)
    assert OWN_LAG_S == 90.0 and got.accepted is accepted, got.reason
    assert ("sleeve or thermowell" in got.reason) is not accepted
    whole = fit.Result(effect, "sensor", "signal", True, theta=[theta], signal="chp.T_sup", effect=e,
                       train_cost=1.0, held_cost=0.5)
    got = verdict._judged(whole, None, 100.0, verdict.bic(2.0, 100.0, 0), 1.0)
    assert got.accepted is accepted, got.reason


def test_an_offset_where_the_tank_is_steep_is_judged_with_the_place_fitted_with_it():
    """The shape check reads the residual the offset's own model leaves (the sensor's place
    fitted together with the offset, as SensorOffset.solve fits them). A -2 K offset on a sensor
    whose tank is steep only while the heating is off: placed without the offset, the place takes
    part of it in that state and the rest looks not constant (labsim realisation 3's -3 K offset
    on sensor 5 kept 0.41 of itself with the CHP off); with it, the offset is alike in every state."""
    from plant.diagnose.replay import Replay
    from plant.diagnose import sensor_height
    from plant.diagnose.sensor_height import HeightFit

    rec = synth.make("none", days=1.0, noise=False)
    ctx = Context.build(rec, train_days=0.5)
    s = "storage.T_sensor_5"
    j = ctx.measured.index(s)
    sim = np.where(np.isfinite(ctx.meas), ctx.meas, 0.0)
    sim[:, j] += 2.0                                    # the lab's sensor reads 2 K low
    steep = ~ctx.flags["heating_on"]
    assert STATE_SHARE < steep[ctx.train].mean() < 1.0 - STATE_SHARE
    g = np.where(steep, 60.0, 0.0)                      # K per tank height; a shift reads s x g
    rows = np.zeros((len(sim), max(ctx.cols) + 1))
    rows[:, ctx.cols] = sim
    ctx = ctx.with_baseline(Replay(rows, heights={s: HeightFit(0.0, 0.03, g)}), (), (), {})
    r = fit.fit_signal(OFFSET, ctx, sim, only=s)
    assert r.theta[0] == pytest.approx(-2.0, abs=0.05) and r.local["unlike"] == ""
    # the old reading of the residual, placed without the offset: not constant
    m = ctx.train & ctx.ok[:, j]
    before = sensor_height.placed(ctx.meas[:, j], sim[:, j], m, ctx.heights[s])
    e = ctx.meas[m, j] - before[m]
    assert OFFSET.unlike([-2.0], e, {k: f[m] for k, f in ctx.states.items()}).startswith("not constant")


def test_no_offset_is_named_on_a_sensor_the_twin_cannot_represent():
    """A sensor at a port reads the port's water in some states and its layer in others: against
    the nominal replay +0.8 K with the heating on, -2 K with it off, beyond its limit both ways
    (unrepresented.find). With its place fitted together with an offset (a steep tank while the
    heating is on), the offset's shape check passes, as it did for rigsim house 2's sensor 2
    (+5.15 K named on null_a); one value cannot be such a sensor's error, so the offset is not
    named on it (Context.unrepresented, fit._unlike)."""
    from dataclasses import replace

    from plant.diagnose import unrepresented
    from plant.diagnose.replay import Replay
    from plant.diagnose.sensor_height import HeightFit

    rec = synth.make("none", days=1.0, noise=False)
    ctx = Context.build(rec, train_days=0.5)
    s = "storage.T_sensor_5"
    j = ctx.measured.index(s)
    sim = np.where(np.isfinite(ctx.meas), ctx.meas, 0.0)
    on = ctx.flags["heating_on"]
    sim[:, j] -= np.where(on, 0.8, -2.0)
    g = np.where(on, 100.0, 0.0)                         # K per tank height: a 2.8 cm shift reads 2.8 K
    rows = np.zeros((len(sim), max(ctx.cols) + 1))
    rows[:, ctx.cols] = sim
    ctx = ctx.with_baseline(Replay(rows, heights={s: HeightFit(0.0, 0.03, g)}), (), (), {})
    found = unrepresented.find(ctx, sim)
    assert list(found) == [s]
    assert fit.fit_signal(OFFSET, ctx, sim, only=s).local["unlike"] == ""   # the shape check alone
    ctx = replace(ctx, unrepresented=found)
    r = fit.fit_signal(OFFSET, ctx, sim, only=s)
    assert r.local["unlike"].startswith(f"{s} cannot be represented by the twin: relative to its neighbours")
    assert not verdict._judged_local(r, n_eff=100.0).accepted
    assert fit.fit_signal(OFFSET, ctx, sim).signal != s
    # a lag may still be named there: its residual changes sign with the tank's rise and fall
    lag = next(e for e in catalogue() if e.id == "sensor_lag")
    assert not lag.same_in_every_state and OFFSET.same_in_every_state


@pytest.mark.parametrize("before, after, accepted", [
    (2.78, 2.24, False),   # rigsim house 2 null_b: -4.5 K on the bottom sensor, 37 % of the excess
    (3.78, 2.59, False),   # collector_degradation_60: -5.7 K, 55 %
    (1.29, 0.59, True),    # rigsim r1 sensor_offset_p1_5: the true +1.5 K, within its limit after
    (3.07, 0.62, True),    # rigsim r1 sensor_offset_m3: the true -3 K, 100 %
])
def test_an_offset_that_leaves_most_of_its_residuals_excess_is_not_named(before, after, accepted):
    """An offset judged on its own residual relative to its neighbours must remove EXPLAIN
    of that residual's excess over its limit: the limit is that residual's accuracy (the plant
    replay's few K, which a plant candidate is held to, do not apply to it). The figures are the
    held-out RMS of the reports of those cases."""
    limit = 0.61
    local = {"heldout_rms_before": before, "heldout_rms_after": after, "gain": 1.0 - (after / before) ** 2,
             "limit": limit, "neighbours": ["storage.T_sensor_2"]}
    r = fit.Result("sensor_offset", "sensor", "signal", True, theta=[-4.47], signal="storage.T_sensor_1",
                   effect=OFFSET, local=local)
    got = verdict._judged_local(r, n_eff=100.0)
    share = 1.0 - (after ** 2 - limit ** 2) / (before ** 2 - limit ** 2)
    assert got.accepted is accepted, got.reason
    assert (share >= verdict.EXPLAIN) is accepted
    if not accepted:
        assert f"removes {share * 100:.0f} % < 60 % of its excess over the limit 0.61" in got.reason
        assert "otherwise than by this effect" in got.reason


def test_a_lag_that_leaves_most_of_its_residuals_excess_is_left_to_the_selection():
    """The rule holds an offset, whose whole shape is a constant, not a lag: rigsim r2's true 300 s
    lag on a top sensor in still water the twin does not resolve removed 42 % of the excess (the
    report's held-out RMS 2.21 -> 1.73 K) and is judged as before."""
    lag = next(e for e in catalogue() if e.id == "sensor_lag")
    local = {"heldout_rms_before": 2.21, "heldout_rms_after": 1.73, "gain": 1.0 - (1.73 / 2.21) ** 2,
             "limit": 0.615, "neighbours": ["storage.T_sensor_9"]}
    r = fit.Result("sensor_lag", "sensor", "signal", True, theta=[928.0], signal="storage.T_sensor_10",
                   effect=lag, local=local)
    got = verdict._judged_local(r, n_eff=100.0)
    assert got.accepted, got.reason
    off = dataclasses.replace(r, id="sensor_offset", theta=[-1.0], effect=OFFSET)
    assert not verdict._judged_local(off, n_eff=100.0).accepted
