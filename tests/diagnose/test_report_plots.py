"""The report's per-subsystem plots (before/after): one PNG per located subsystem, listed in
report.json `plots` and linked from report.md's "## Subsystems" table.

One real diagnosis of a 1.5-day labsim recording with a leaking mixing valve (cut replay: five
subsystems, a fitted candidate, so the plots carry the "after" twin); about 25 s.
"""
import json
import math
import re

import matplotlib.image as mpimg
import numpy as np
import pytest

from plant.catalogue import CATALOGUE
from plant.diagnose import diagnose, plots, recording_io
from labsim.suite import make_case

UNIT = lambda s: CATALOGUE.signal(s).unit  # noqa: E731  (house 1's units)

DAYS, TRAIN, DPI = 1.5, 0.6, 80


@pytest.fixture(scope="module")
def diagnosed(tmp_path_factory):
    d = tmp_path_factory.mktemp("valve_leak_20")
    make_case("valve_leak_20", d / "rec", days=DAYS)
    rec = recording_io.load(d / "rec" / "recording.csv", d / "rec" / "columns.toml")
    rep = diagnose(rec, train_days=TRAIN, out=d / "out", plots=True, log=lambda *a: None)
    return rep, d / "out"


def test_every_located_subsystem_has_a_readable_plot_and_the_report_lists_exactly_the_files(diagnosed):
    rep, out = diagnosed
    on_disk = json.loads((out / "report.json").read_text())["plots"]
    assert on_disk == rep["plots"]
    subs = rep["locate"]["subsystems"]
    assert len(subs) >= 3  # the cut replay compares generators, storage, circuit, ...
    files = on_disk["subsystems"]
    assert set(files) == {d["subsystem"] for d in subs}
    for name, f in files.items():
        assert f == f"subsystem_{name.lower().replace(' ', '_')}.png"
    listed = {on_disk["overview"], *on_disk["windows"], *files.values()}
    assert listed == {p.name for p in out.glob("*.png")}
    for name, f in files.items():
        img = mpimg.imread(out / f)
        h, w = img.shape[:2]
        assert w == 11 * DPI
        # the figure grows by a fixed height per axis: the image has as many axes as its spec
        n_axes = len(on_disk["subsystem_axes"][name])
        assert h == pytest.approx(DPI * (0.9 + 2.3 * n_axes), abs=1), (name, h, n_axes)
        assert img[..., :3].std() > 0.05  # not blank


def test_the_largest_error_share_is_plotted_with_its_worst_mismatched_signals(diagnosed):
    rep, out = diagnosed
    subs = rep["locate"]["subsystems"]
    top = max(subs, key=lambda d: d["error_share"])
    assert top["subsystem"] in rep["plots"]["subsystems"] and top["mismatched_signals"]
    for d in subs:
        axes = rep["plots"]["subsystem_axes"][d["subsystem"]]
        pool = d["mismatched_signals"] or d["signals"]
        assert 1 <= len(axes) <= plots.PLOT_AXES
        assert len({a["unit"] for a in axes}) == len(axes)
        for a in axes:
            assert 1 <= len(a["signals"]) <= plots.PLOT_PER_AXIS
            assert all(s in pool and CATALOGUE.signal(s).unit == a["unit"] for s in a["signals"])
            # the shown signals are those of their unit with the largest held-out RMSE (nominal twin)
            err = {s: rep["signals"][s]["heldout_rmse_before"] for s in pool if CATALOGUE.signal(s).unit == a["unit"]}
            left_out = [err[s] for s in err if s not in a["signals"]]
            shown = [err[s] for s in a["signals"]]
            assert shown == sorted(shown, reverse=True)
            if left_out:
                assert min(shown) >= max(left_out)
                assert len(shown) == plots.PLOT_PER_AXIS  # more of one unit than an axis holds: capped


def test_the_held_out_window_is_shaded(diagnosed):
    rep, out = diagnosed
    img = mpimg.imread(out / rep["plots"]["subsystems"]["storage"])[..., :3]
    shade = np.all(np.abs(img - 0.88) < 0.01, axis=-1)
    cols = np.flatnonzero(shade.sum(axis=0) > 0.15 * img.shape[0])
    assert cols.size > 0.2 * img.shape[1]
    # the held-out window is the last 60 % of the time axis, which spans about 7-76 % of the width
    start = rep["heldout_window_h"][0] / (DAYS * 24)
    assert cols.min() / img.shape[1] == pytest.approx(0.07 + 0.69 * start, abs=0.03)


def test_report_md_links_each_plot_in_its_subsystem_row(diagnosed):
    rep, out = diagnosed
    md = (out / "report.md").read_text()
    section = md.split("## Subsystems", 1)[1]
    rows = [line for line in section.splitlines() if line.startswith("| ") and not line.startswith("| subsystem")]
    rows = rows[: len(rep["locate"]["subsystems"])]
    for d, row in zip(rep["locate"]["subsystems"], rows):
        cells = [c.strip() for c in row.strip("|").split("|")]
        assert cells[0] == d["subsystem"]
        assert int(cells[1]) == round(100 * d["error_share"])
        assert re.fullmatch(r"!\[(.+)\]\((.+\.png)\)", cells[-1]).groups() == (
            d["subsystem"], rep["plots"]["subsystems"][d["subsystem"]])


def test_without_plots_nothing_is_listed(tmp_path):
    rec = recording_io.load(*_short(tmp_path))
    rep = diagnose(rec, train_days=0.3, out=tmp_path / "out", plots=False, log=lambda *a: None,
                   effects=[], refit_nominal=False)
    assert rep["plots"] == {} and not list((tmp_path / "out").glob("*.png"))
    assert "| - |" in (tmp_path / "out" / "report.md").read_text().split("## Subsystems", 1)[1]


def _short(d):
    make_case("valve_leak_20", d / "rec", days=0.6)
    return d / "rec" / "recording.csv", d / "rec" / "columns.toml"


def test_plot_axes_prefer_mismatched_signals_one_axis_per_unit_worst_first():
    temps = [f"storage.T_sensor_{i}" for i in range(1, 8)]
    others = ["boiler.m_flow", "boiler.Q_flow", "chp.P_el"]
    err = {s: float(i) for i, s in enumerate(temps)} | {"boiler.m_flow": 50.0, "boiler.Q_flow": 3.5,
                                                         "chp.P_el": math.nan}
    axes = plots.plot_axes(temps + others, temps + others, err, UNIT)
    assert [a["unit"] for a in axes] == ["kg/s", "degC", "W"]
    assert axes[1]["signals"] == temps[::-1][: plots.PLOT_PER_AXIS]
    assert axes[2]["signals"] == ["boiler.Q_flow", "chp.P_el"]  # never scored: last
    # only the mismatched signals when there are any; all of them when there are none
    assert plots.plot_axes(temps + others, ["chp.P_el"], err, UNIT) == [{"unit": "W", "signals": ["chp.P_el"]}]
    assert len(plots.plot_axes(temps + others, [], err, UNIT)) == 3
    # a signal without any measured value (not in err) is not plotted
    assert plots.plot_axes(["zone.T_room"], ["zone.T_room"], err, UNIT) == []


def test_ten_mismatched_sensors_of_one_unit_are_capped_to_the_worst():
    # (the labsim diagnosis above had all ten storage sensors mismatched while one value stood for
    # both switch headers; each calibrated on its own sensor, one is left)
    sensors = [f"storage.T_sensor_{k}" for k in range(1, 11)]
    err = {s: float(k) for k, s in enumerate(sensors, 1)} | {"storage.Q": 9.0}
    axes = plots.plot_axes(sensors + ["storage.Q"], sensors + ["storage.Q"], err,
                           lambda s: "W" if s.endswith(".Q") else "degC")
    assert axes[0] == {"unit": "degC", "signals": sensors[::-1][:plots.PLOT_PER_AXIS]}
    assert axes[1] == {"unit": "W", "signals": ["storage.Q"]}
