"""The report's figures: overview and mismatch windows, and one before/after figure per located
subsystem (measured, nominal twin, fitted twin; held-out window shaded)."""
from __future__ import annotations

import math

import numpy as np



PLOT_AXES = 3      # unit axes per subsystem plot: temperatures, flows, powers
PLOT_PER_AXIS = 4  # signals per axis; more, each drawn three times, hide one another
QUANTITY = {"degC": "temperature", "kg/s": "mass flow", "W": "power", "kg": "mass"}


def write_plots(rep, out, ctx, nominal_rows, best) -> dict:
    """Writes the PNGs; returns report.json `plots`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sig = (rep["affected_signals"] or sorted(rep["signals"], key=lambda s: -(rep["signals"][s]["rmse_before"] or 0)))[:3]
    t = ctx.rec.time / 3600.0
    after = best.sim if best is not None else None
    wins = rep["locate"]["windows"][:2] or [{"start_h": t[0], "end_h": t[-1]}]
    files = []
    for wi, w in enumerate([{"start_h": t[0], "end_h": t[-1]}] + wins):
        pad = 0 if wi == 0 else 3.0
        sel = (t >= w["start_h"] - pad) & (t <= w["end_h"] + pad)
        fig, ax = plt.subplots(len(sig), 1, figsize=(11, 2.8 * len(sig)), sharex=True, squeeze=False)
        for a, s in zip(ax[:, 0], sig):
            j = ctx.measured.index(s)
            a.plot(t[sel], ctx.meas[sel, j], lw=0.8, label="measured", color="k")
            a.plot(t[sel], nominal_rows[sel, ctx.cols[j]], lw=0.8, label="twin (nominal)")
            if after is not None:
                a.plot(t[sel], after[sel, j], lw=0.8, ls="--", label=f"twin + {best.id}")
            a.set_ylabel(f"{s} [{ctx.unit(s)}]", fontsize=8)
            a.legend(fontsize=7, ncol=3)
        ax[-1, 0].set_xlabel("hours since recording start")
        fig.suptitle("whole recording" if wi == 0 else f"located window {wi}: {w['start_h']:.1f}-{w['end_h']:.1f} h")
        fig.tight_layout()
        files.append("overview.png" if wi == 0 else f"window_{wi}.png")
        fig.savefig(out / files[-1], dpi=80)
        plt.close(fig)
    subs, axes = subsystem_plots(rep, out, ctx, nominal_rows, best, plt)
    return {"overview": files[0], "windows": files[1:], "subsystems": subs, "subsystem_axes": axes}


def slug(name: str) -> str:
    return name.lower().replace(" ", "_")


def heldout_error(ctx, sim, mask) -> dict:
    """Normalised held-out mean squared error per plottable signal (the measure of locate's error
    shares, so that it ranks a subsystem's flows against its temperatures)."""
    z = ctx.per_signal_mse(sim, mask) / ctx.scale ** 2
    return {s: float(z[j]) for j, s in enumerate(ctx.measured) if np.isfinite(ctx.meas[:, j]).any()}


def plot_axes(signals, mismatched, err, unit) -> list[dict]:
    """A subsystem plot's axes [{unit, signals}]: its mismatched signals (all of them when none
    is), per catalogue unit the PLOT_PER_AXIS with the largest held-out error, the unit with the
    largest error on top. err: {signal: held-out error}; a signal not in it is not plotted;
    unit: signal -> its unit (Context.unit)."""
    def rank(s):
        return err[s] if math.isfinite(err[s]) else -1.0  # never scored held-out: last

    pool = [s for s in (mismatched or signals) if s in err] or [s for s in signals if s in err]
    by_unit: dict = {}
    for s in sorted(pool, key=lambda s: -rank(s)):
        by_unit.setdefault(unit(s), []).append(s)
    return [{"unit": u, "signals": sig[:PLOT_PER_AXIS]} for u, sig in list(by_unit.items())[:PLOT_AXES]]


def subsystem_plots(rep, out, ctx, nominal_rows, best, plt) -> tuple[dict, dict]:
    """subsystem_<slug>.png per located subsystem: measured, nominal twin (before) and fitted twin
    (after) over the whole recording, the held-out window (where the error shares are measured)
    shaded. Returns {subsystem: file}, {subsystem: axes}."""
    from matplotlib.lines import Line2D
    from matplotlib.patches import Patch

    sim0 = nominal_rows[:, ctx.cols]
    mask = ctx.held if ctx.held.any() else ctx.train | ctx.held
    err = heldout_error(ctx, sim0, mask)
    t = ctx.rec.time / 3600.0
    held = rep["heldout_window_h"]
    after = best.sim if best is not None else None
    styles = [("measured", dict(lw=1.6, alpha=0.45)), ("nominal twin (before)", dict(lw=0.9, ls=":"))]
    if after is not None:
        styles.append((f"twin + {best.id} (after)", dict(lw=0.9, ls="--")))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    files, specs = {}, {}
    for d in rep["locate"].get("subsystems", []):
        axes = plot_axes(d["signals"], d["mismatched_signals"], err, ctx.unit)
        if not axes:
            continue
        fig, ax = plt.subplots(len(axes), 1, figsize=(11, 0.9 + 2.3 * len(axes)), sharex=True, squeeze=False)
        for a, spec in zip(ax[:, 0], axes):
            if held:
                a.axvspan(held[0], held[1], color="0.88", lw=0, zorder=0)
            for c, s in zip(colours, spec["signals"]):
                j = ctx.measured.index(s)
                ys = [ctx.meas[:, j], nominal_rows[:, ctx.cols[j]]] + ([after[:, j]] if after is not None else [])
                for y, (_, st) in zip(ys, styles):
                    a.plot(t, y, color=c, **st)
            # one entry per signal (colour) and per source (line style), not one per line
            handles = [Line2D([], [], color=c, lw=1.6, label=s) for c, s in zip(colours, spec["signals"])]
            handles += [Line2D([], [], color="k", **st, label=lab) for lab, st in styles]
            if held:
                handles.append(Patch(color="0.88", label="held-out window"))
            a.legend(handles=handles, fontsize=7, loc="upper left", bbox_to_anchor=(1.01, 1.0), frameon=False)
            a.set_ylabel(f"{QUANTITY.get(spec['unit'], 'value')} [{spec['unit']}]", fontsize=8)
            a.tick_params(labelsize=7)
        ax[-1, 0].set_xlim(t[0], t[-1])
        ax[-1, 0].set_xlabel("hours since recording start", fontsize=8)
        mode = (f"concentrates in '{d['mode']}' (x{d['mode_concentration']:.2f})" if d.get("mode")
                else "no operating mode stands out")
        fig.suptitle(f"{d['subsystem']}: {100 * d['error_share']:.0f} % of the held-out error, {mode}", fontsize=10)
        # fixed margins: tight_layout would draw the figure once more (a third of its cost)
        fig.subplots_adjust(left=0.07, right=0.76, top=1 - 0.45 / fig.get_figheight(),
                            bottom=0.45 / fig.get_figheight(), hspace=0.12)
        files[d["subsystem"]] = f"subsystem_{slug(d['subsystem'])}.png"
        specs[d["subsystem"]] = axes
        fig.savefig(out / files[d["subsystem"]], dpi=80)
        plt.close(fig)
    return files, specs
