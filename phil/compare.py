"""Comparison of a PHIL run (`twin phil compare RUN`): set vs measured per interface, and the run
against the same house simulated alone on the same type day, as the reference's figures do.

Per bench interface (a set-point and the measurement that shows whether the bench followed it,
phil/wiring.py's pairs), from the run's recording: RMS and mean of set minus measured, largest
deviation, and one figure per bench (set and measured over time). Then the house with all of its
own hardware simulated (ALONE: house 1's file has no collector, so house1_solar.toml, the one its
PHIL variant simulates added; houses 2-5 their own files: heat pumps, boilers, CHPs, storages,
valves) on the same type-day window, its room set-points those of the PHIL variant (house 1's
has no night set-back): per interface the run had a bench for, the PHIL house's heat against the
house alone's (space heating: the emitter's heat; hot water; solar; SF3's brine: the ground
collector's heat), the room temperature when the run had the space-heating bench, and what the
simulated generators and storages did (heat per generator, storage top and bottom temperatures
and SOC) where the PHIL run had the lab's. What cannot be compared is said: the grid (the house
alone draws from no grid outside a district run), the room without a space-heating bench (the
PHIL house is then unheated). Written to the run directory: compare.md, compare_<bench>.png,
compare_house.png.
"""
from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from phil.benchmap import load_bench_map
from phil.wiring import WIRINGS
from plant.errors import ConfigError
from profiles.recording import read_recording

#: the house simulated alone, per PHIL house ([house] name of its variant)
ALONE = {"house1": "house1_solar", "house2": "house2", "house3": "house3", "house4": "house4", "house5": "house5"}
#: per bench, the PHIL house's simulated heat [W] compared with the same signal of the house alone
BENCH_HEAT = {"tap_water": ("dhw.Q_flow", "hot water"), "solar": ("solar.Q_flow", "solar heat"),
              "brine": ("ground.Q_flow", "heat from the ground (brine)")}
EMITTERS = (("radiator.Q_flow", "heat to the radiators"), ("floor.Q_flow", "heat to the floor heating"))
ROOM = ("zone.T_room", "room temperature", "degC")
NOT_ALONE = {"grid": "the grid; the house alone draws from no grid (outside a district run its substation is "
                     "off, substation_control.active = 0): `twin district` simulates it on one"}


def phil_house(meta: dict) -> str:
    """The [house] name of the run's PHIL variant (house1 ... house5)."""
    from phil.options import house_file
    from plant.declaration import load

    return load(house_file(str(meta.get("house", "")))).name


def house_signals(rec: Any) -> list[tuple[str, str, str]]:
    """(signal, label, unit) the run has and the house alone is compared on: the room and the
    emitter's heat with the space-heating bench, each other bench's heat."""
    benches = rec.meta.get("benches", {})
    out = []
    if "space_heating" in benches:
        out.append(ROOM)
        out += [(n, label, "W") for n, label in EMITTERS if n in rec.names]
    out += [(BENCH_HEAT[b][0], BENCH_HEAT[b][1], "W") for b in benches if b in BENCH_HEAT]
    return [s for s in out if s[0] in rec.names]


def interfaces(rec: Any) -> dict[str, list[dict[str, Any]]]:
    """Per bench, per pair: the follow statistics over the run (warm-up included)."""
    out: dict[str, list[dict[str, Any]]] = {}
    for bench in rec.meta.get("benches", {}):
        unit = {p.name: p.unit for p in load_bench_map(bench).dmap.points}
        rows = []
        for s, m in WIRINGS[bench].pairs:
            if f"{bench}.{s}" not in rec.names:
                continue
            d = rec.column(f"{bench}.{s}") - rec.column(f"{bench}.{m}")
            d = d[~np.isnan(d)]
            rows.append({"set": s, "measured": m, "unit": unit[s], "n": len(d),
                         "rms": float(np.sqrt(np.mean(d ** 2))) if len(d) else None,
                         "mean": float(d.mean()) if len(d) else None,
                         "max_abs": float(np.abs(d).max()) if len(d) else None})
        out[bench] = rows
    return out


def simulate_alone(meta: dict, t: np.ndarray, signals: list[str]) -> dict[str, Any]:
    """The house with its own hardware on the run's type day, sampled at the run's times: the
    signals asked for, its storages' top, bottom and SOC, and its heat per generator [kWh]."""
    from plant.declaration import load
    from plant.house import load_house
    from phil.options import house_file

    typeday = int(meta.get("typeday") or 0)
    zone = load(house_file(str(meta.get("house", "")))).instances["zone"].params
    overrides = {"zone.T_night": zone.T_night, "zone.T_day": zone.T_day,
                 **({"profiles.typeday": typeday} if typeday else {})}
    name = ALONE[phil_house(meta)]
    house = load_house(name, controller="rule_based", overrides=overrides)
    storages = [i.name for i in house.decl.instances.values() if i.kind in ("storage", "storage_fmu")]
    names = list(signals) + [f"{s}.{q}" for s in storages for q in ("T_top", "T_bot", "SOC")]
    out: dict[str, Any] = {n: np.full(len(t), math.nan) for n in names}
    start = t[0] - float(meta.get("dt", 1.0))
    if start > 0:
        house.step(start)
    L0 = house.ledger()
    for k, tk in enumerate(t):
        house.step(max(tk - house.t, 1e-3))
        for n in names:
            out[n][k] = house.get(n)
    L1 = house.ledger()
    out["house"], out["storages"] = name, names[len(signals):]
    out["generators_kWh"] = {k.removeprefix("heat_"): (L1[k] - L0.get(k, 0.0)) / 3.6e6 for k in L1
                             if k.startswith("heat_") and k not in ("heat_generators", "heat_building", "heat_dhw")}
    return out


def _energy(t: np.ndarray, q: np.ndarray) -> float:
    dt = np.diff(t, prepend=t[0] - (t[1] - t[0] if len(t) > 1 else 0.0))
    return float(np.nansum(q * dt) / 3.6e6)


def house_table(rec: Any, alone: dict[str, Any]) -> list[dict[str, Any]]:
    rows = []
    for name, label, unit in house_signals(rec):
        phil, sim = rec.column(name), alone[name]
        if unit == "W":
            a, b = _energy(rec.time, phil), _energy(rec.time, sim)
            rows.append({"quantity": f"{label} [kWh]", "phil": a, "alone": b,
                         "difference_pct": 100.0 * (a - b) / b if abs(b) > 1e-9 else None})
        else:
            rows.append({"quantity": f"{label} mean [{unit}]", "phil": float(np.nanmean(phil)),
                         "alone": float(np.nanmean(sim)), "rms_difference": float(np.sqrt(np.nanmean((phil - sim) ** 2)))})
    return rows


def not_compared(rec: Any) -> list[str]:
    """What of the run is not compared with the house alone, and why."""
    benches = rec.meta.get("benches", {})
    out = [NOT_ALONE[b] for b in benches if b in NOT_ALONE]
    if "space_heating" not in benches:
        out.append("the room; without the space-heating bench the PHIL house is unheated "
                   "(its heating circuit's measured flow stays 0)")
    return out


def compare(run: str | Path, plots: bool = True) -> dict[str, Any]:
    rec = read_recording(run)
    if rec.meta.get("kind") != "phil":
        raise ConfigError(f"{run}: not a PHIL run (meta.json kind = {rec.meta.get('kind')!r}); "
                          "give a directory written by twin phil --record")
    result: dict[str, Any] = {"run": str(run), "interfaces": interfaces(rec), "not_compared": not_compared(rec)}
    signals = [n for n, _, _ in house_signals(rec)]
    known = phil_house(rec.meta) in ALONE
    alone = simulate_alone(rec.meta, rec.time, signals) if known else None
    if alone is not None:
        result["alone_house"] = alone["house"]
        result["house"] = house_table(rec, alone)
        result["alone_generators_kWh"] = alone["generators_kWh"]
        result["alone_storages"] = {n: {"mean": float(np.nanmean(alone[n])), "min": float(np.nanmin(alone[n])),
                                        "max": float(np.nanmax(alone[n]))} for n in alone["storages"]}
    else:
        result["house_alone"] = (f"no house simulated alone for {rec.meta.get('house')!r} (a PHIL house "
                                 f"file of no shipped house; known: {', '.join(ALONE)}); set vs measured only")
    out = Path(run)
    (out / "compare.md").write_text(to_markdown(result))
    if plots:
        result["plots"] = _plots(rec, alone, out)
    return result


def to_markdown(result: dict[str, Any]) -> str:
    f = lambda v: "n/a" if v is None else f"{v:.4g}"  # noqa: E731
    lines = [f"# PHIL run {result['run']}: set vs measured", "",
             "| bench | set-point | measured | unit | RMS | mean (set - measured) | largest |", "|---|---|---|---|---|---|---|"]
    for bench, rows in result["interfaces"].items():
        lines += [f"| {bench} | {r['set']} | {r['measured']} | {r['unit']} | {f(r['rms'])} | {f(r['mean'])} | "
                  f"{f(r['max_abs'])} |" for r in rows]
    if "house" not in result:
        return "\n".join(lines + ["", result.get("house_alone", ""), *result["not_compared"], ""])
    lines += ["", f"## Against the house simulated alone ({result['alone_house']}, same type day and window)", "",
              "| quantity | PHIL | alone | difference |", "|---|---|---|---|"]
    for r in result["house"]:
        diff = f"{f(r['difference_pct'])} %" if "difference_pct" in r else f"RMS {f(r['rms_difference'])}"
        lines.append(f"| {r['quantity']} | {f(r['phil'])} | {f(r['alone'])} | {diff} |")
    lines += ["", "Simulated alone, where the PHIL run had the lab's hardware: heat per generator [kWh] "
              + ", ".join(f"{k} {v:.3f}" for k, v in result["alone_generators_kWh"].items()) + "; "
              + ", ".join(f"{k} {v['min']:.1f}…{v['max']:.1f} (mean {v['mean']:.1f})"
                          for k, v in result["alone_storages"].items()), ""]
    return "\n".join(lines + [f"Not compared: {n}" for n in result["not_compared"]] + [""])


def _plots(rec: Any, alone: dict[str, Any] | None, out: Path) -> list[str]:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = rec.time / 3600.0
    files = []
    for bench in rec.meta.get("benches", {}):
        pairs = [(s, m) for s, m in WIRINGS[bench].pairs if f"{bench}.{s}" in rec.names]
        fig, axes = plt.subplots(len(pairs), 1, figsize=(11, 2.6 * len(pairs)), sharex=True, squeeze=False)
        for ax, (s, m) in zip(axes[:, 0], pairs):
            ax.plot(t, rec.column(f"{bench}.{s}"), lw=0.8, label=f"set {s}")
            ax.plot(t, rec.column(f"{bench}.{m}"), lw=0.8, label=f"measured {m}", alpha=0.8)
            ax.legend(fontsize=7)
        axes[-1, 0].set_xlabel("time [h]")
        fig.suptitle(f"{bench}: set vs measured")
        fig.tight_layout()
        fig.savefig(out / f"compare_{bench}.png", dpi=90)
        plt.close(fig)
        files.append(f"compare_{bench}.png")
    shown = house_signals(rec)
    if alone is None or not shown:
        return files
    fig, axes = plt.subplots(len(shown), 1, figsize=(11, 2.4 * len(shown)), sharex=True, squeeze=False)
    for ax, (n, label, unit) in zip(axes[:, 0], shown):
        ax.plot(t, rec.column(n), lw=0.8, label="PHIL")
        ax.plot(t, alone[n], lw=0.8, label=f"simulated alone ({alone['house']})", alpha=0.8)
        ax.set_ylabel(f"{label} [{unit}]", fontsize=8)
        ax.legend(fontsize=7)
    axes[-1, 0].set_xlabel("time [h]")
    fig.tight_layout()
    fig.savefig(out / "compare_house.png", dpi=90)
    plt.close(fig)
    return files + ["compare_house.png"]
