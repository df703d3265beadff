"""Operating modes of a unit the twin cannot represent: identified, reported, kept from blocking.

A real unit has protections and habits of its own that the twin's model of it lacks: a boiler
that locks out while its return is too hot and fires again below a release temperature, a CHP
that trips. While the recording's unit runs and the replay's does not (or the reverse), every
signal of that unit differs by its whole output, an hour at a time: rigsim's boiler locked out
at 0.75 % of the samples (with 0.37 % of run-on the other way) and its heat and gas failed
Guideline 14 hourly (33-37 % CV) in a case with no effect, which made every verdict
`unexplained_mismatch`.

So after the first nominal replay, the samples where a unit's recorded running state (its
measured output above a threshold) differs from the replay's are identified per unit, reported
(`unit_modes` in report.json: samples, share of the unit's running samples, why) and not scored
for that unit's own signals. A missing effect that changes how much a running unit gives (a
fouled boiler: 12 % less heat) leaves the states alike and stays scored. When the states differ
at more than MAX_SHARE of the unit's running samples it is no longer a mode of the unit but a
difference in how it is run: nothing is masked, and the report says so.
"""
from __future__ import annotations

import dataclasses

import numpy as np

# a fifth of the unit's running samples: a lock-out or a trip is occasional; beyond it the
# states differ because the unit is run differently, which is for the diagnosis to see
MAX_SHARE = 0.2


def identify(rec, rows: np.ndarray, catalogue_index, ran: dict) -> dict:
    """{unit: {mask (samples whose state differs), samples, share, masked, why}} for the units the
    recording measures; rows: a replay's catalogue rows; catalogue_index: name -> column; ran:
    unit -> (the signal whose recorded value says it ran, the threshold in its unit: roles.Roles.ran)."""
    out = {}
    n = len(rows)
    for unit, (sig, thr) in ran.items():
        if not rec.has(sig):
            continue
        meas = rec.data[sig][:n]
        sim = rows[:, catalogue_index(sig)]
        ok = np.isfinite(meas) & np.isfinite(sim)
        runs_lab, runs_twin = (meas > thr) & ok, (sim > thr) & ok
        differ = runs_lab != runs_twin
        running = int((runs_lab | runs_twin).sum())
        share = float(differ.sum() / running) if running else 0.0
        masked = bool(differ.any() and share <= MAX_SHARE)
        out[unit] = {"mask": differ if masked else np.zeros(n, bool), "samples": int(differ.sum()),
                     "lab_switches": int(np.count_nonzero(np.diff(runs_lab.astype(np.int8)))),
                     "lab_runs": int(runs_lab.sum()), "lab_runs_twin_not": int((runs_lab & ~runs_twin).sum()),
                     "twin_runs_lab_not": int((runs_twin & ~runs_lab).sum()),
                     "share_of_running": share, "masked": masked,
                     "why": ("occasional states the twin's unit model does not have (a lock-out, a trip, a "
                             "run-on): those samples are not scored for the unit's own signals" if masked else
                             f"the states differ at {100 * share:.0f} % of the running samples (> "
                             f"{100 * MAX_SHARE:.0f} %): scored, as a difference in how the unit is run")
                     if differ.any() else "the recorded and replayed states agree"}
    return out


def run_otherwise(m: dict) -> bool:
    """Whether a unit's recorded running state (an identify entry) differs from the twin's at more
    samples than the recording switches it on or off: a scan's timing may put one sample of each
    switch on either side (a replay of the twin's own day of house 4 differs at 1 sample), more
    means the lab's unit starts, stops or locks out where the twin's model of it would not, and
    the heat it gives the plant is not the model's. pipeline.outlets replays such a unit from its
    measured outlet where the recording has it; MAX_SHARE only decides whether its differing
    samples are masked for its own signals. (Cut only beyond MAX_SHARE, rigsim realisation 1's
    boiler, differing at 16-19 % of its running samples, 232-271 samples against 118-140
    switches, stayed simulated, and null_b and idle_flow_large were wrong; cut, both were right.)"""
    return m["samples"] > m["lab_switches"]


def apply(ctx, modes: dict):
    """The context with the masked samples dropped from the scoring of each unit's own signals
    (ctx.ok)."""
    ok = ctx.ok.copy()
    for unit, m in modes.items():
        if not m["masked"]:
            continue
        for j, s in enumerate(ctx.measured):
            if s.split(".", 1)[0] == unit:
                ok[: len(m["mask"]), j] &= ~m["mask"]
    return dataclasses.replace(ctx, ok=ok)


def public(modes: dict) -> dict:
    return {u: {k: v for k, v in m.items() if k != "mask"} for u, m in modes.items()}


__all__ = ["identify", "run_otherwise", "apply", "public", "MAX_SHARE"]
