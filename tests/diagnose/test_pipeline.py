"""The diagnosis as stages (plant/diagnose/pipeline.py): each returns a value and changes none of
its inputs, so a stage can be run, inspected and run again on the same inputs."""
import dataclasses

import numpy as np
import pytest

from plant.diagnose import pipeline
from plant.truth import synth
from tests.diagnose.test_cut_replay import CIRCUIT

quiet = lambda *a: None  # noqa: E731


def test_stages_return_new_values_and_leave_their_inputs_as_they_were():
    rec = synth.make("none", days=1.0, signals=CIRCUIT, seed=3)
    p = pipeline.prepare(rec, "house1", train_days=0.5, require_cut=False)
    assert p.replayer.circuit and p.replayer.emitter and p.replayer.t_train == p.ctx.t_split
    ok0, base0 = p.ctx.ok.copy(), dict(p.replayer.base)
    b = pipeline.calibrate(p, "house1", refit_nominal=False, log=quiet)
    # the calibrations came back as a new replayer and a new context; the prepared ones are as they were
    assert b.replayer is not p.replayer and p.replayer.base == base0 and not p.replayer.calibrated
    assert b.replayer.calibrated == {"radiator"} and set(b.emitter["values"]) <= set(b.replayer.base)
    assert p.ctx.nominal is None and np.array_equal(p.ctx.ok, ok0)
    assert b.ctx.nominal is b.nominal and np.array_equal(b.ctx.nominal_sim, b.nominal.rows[:, b.ctx.cols])
    # a replay is a value: the same replayer gives the same rows, and its reading fits come with it
    again = b.replayer.run()
    assert np.array_equal(again.rows, b.nominal.rows, equal_nan=True) and set(again.pipe) == set(b.nominal.pipe)
    with pytest.raises(dataclasses.FrozenInstanceError):
        b.ctx.nominal_sim = None
    loc = pipeline.locate_mismatch(b)
    results = pipeline.fit_candidates(b, None, jobs=1, log=quiet)
    sel = pipeline.select(b, loc, results)
    # judging gives new results: the fitted ones are not judged in place
    assert all(np.isnan(r.held_gain) and not r.accepted for r in results if r.plausible)
    assert {r.id for r in sel.results} == {r.id for r in results}
    assert any(np.isfinite(r.held_gain) for r in sel.results if r.plausible)
    with pytest.raises(dataclasses.FrozenInstanceError):
        sel.results[0].reason = "changed"
    rep = pipeline.build_report(b, loc, sel, "house1")
    assert rep["verdict"] == sel.verdict and rep["emitter_calibration"] is b.emitter
