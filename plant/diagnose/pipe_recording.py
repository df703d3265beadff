"""A pipe recording (measured inlet and outlet temperature and flow) and its replay through the pipe kind.

A pipe recording is a directory (profiles/recordings/pipes/<test>/) with
  recording.csv   time [s] and the measured columns,
  columns.toml    the project's columns file: [columns] "col" = { signal = "...", unit = "..." } with the
                  signals pipe.T_in, pipe.T_out (the path's inlet and outlet water), the flows the
                  segments name (pipe.m_flow for a single pipe) and optionally pipe.T_env,
  pipe.toml       [pipe] T_env (degC, or T_env_signal), T_init (degC; absent: not initialised),
                  inlet/outlet signals; [[segment]] per pipe in series from inlet to outlet: length,
                  inner_diameter, U [W/(m K)], wall_thickness, wall_density, wall_cp, flow = [signals
                  whose sum is the segment's flow].
The replay runs the segments (plant/grid/pipe.py) in series on the measured inlet temperature and
flows; `Options` switches the pipe kind's options and the diagnosis's sensor and meter effects.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from profiles.recording import read_recording

from .. import units as unit_table
from ..errors import ConfigError
from ..grid.pipe import Pipe, wall_capacity
from ..water import CP, RHO

MAX_STEP = 300.0   # s: longest replay sub-step (a third of the AIT's 900 s samples; ULg samples are 3 s)
FIX = ("map it in {cols}: \"<your column>\" = {{ signal = \"{sig}\", unit = \"{unit}\" }} "
       "(the column must hold the measured {what})")


@dataclass
class Segment:
    name: str
    length: float
    diameter: float
    U: float
    flow: tuple
    C_steel: float          # J/K, the published wall's mass x cp (0 when not given)

    @property
    def mass(self) -> float:
        return RHO * math.pi * self.diameter ** 2 / 4.0 * self.length


@dataclass
class PipeRecording:
    source: Path
    time: np.ndarray
    T_in: np.ndarray
    T_out: np.ndarray           # NaN where not measured
    T_env: np.ndarray
    flows: dict                 # signal -> kg/s
    segments: list
    T_init: float | None
    T_env_declared: float | None
    reference: tuple | None = None   # (time, outlet degC) of the published Modelica result, if shipped
    warnings: list = field(default_factory=list)

    def flow(self, seg: Segment) -> np.ndarray:
        return sum(self.flows[s] for s in seg.flow)

    def delay(self) -> float:
        """Transport delay of the path at each segment's median (non-zero) flow [s]."""
        out = 0.0
        for seg in self.segments:
            f = np.abs(self.flow(seg))
            out += seg.mass / max(float(np.median(f[f > 0])) if np.any(f > 0) else 1e-9, 1e-9)
        return out


@dataclass(frozen=True)
class Options:
    """What the replay adds to the declared pipe (all off = the plain pipe kind)."""
    C_wall: float = 0.0         # J/K over the path, shared by the segments as their steel walls
    wall_share_b: float = 1.0   # at each segment's outlet, as the Modelica PlugFlowPipe lumps it
    dispersion: float = 0.0     # m2/s
    U_factor: float = 1.0
    flow_factor: float = 1.0
    T_env_offset: float = 0.0   # K
    sensor_tau: float = 0.0     # s, first-order lag of the outlet sensor


def _col(rec, signal: str):
    for col, sig in rec.signals.items():
        if sig == signal and col in rec.names:
            return col
    return None


def _signal(rec, signal, unit, cols, what, required=True):
    col = _col(rec, signal)
    if col is None:
        if not required:
            return None
        raise ConfigError(f"{cols}: no column holds {signal} ({what}); " + FIX.format(cols=cols, sig=signal,
                                                                                      unit=unit, what=what))
    v = np.asarray(rec.column(col), dtype=float)
    return unit_table.convert(v, rec.units.get(col, unit), unit, where=f"{cols}: [columns] {col!r}")


def _filled(v: np.ndarray, t: np.ndarray, where: str, what: str, fix: str) -> np.ndarray:
    ok = np.isfinite(v)
    if not ok.any():
        raise ConfigError(f"{where}: the {what} is empty or all NaN; {fix}")
    return v if ok.all() else np.interp(t, t[ok], v[ok])


def _segments(doc: dict, where: Path) -> list:
    segs = doc.get("segment")
    if not isinstance(segs, list) or not segs:
        raise ConfigError(f"{where}: needs at least one [[segment]] (length, inner_diameter, U, flow = [...])")
    out = []
    for i, s in enumerate(segs):
        try:
            C = wall_capacity(s["length"], s["inner_diameter"], s["wall_thickness"], s.get("wall_density", 7850.0),
                              s.get("wall_cp", 480.0)) if "wall_thickness" in s else 0.0
            out.append(Segment(str(s.get("name", f"segment{i + 1}")), float(s["length"]), float(s["inner_diameter"]),
                               float(s["U"]), tuple(s.get("flow", ["pipe.m_flow"])), C))
        except KeyError as exc:
            raise ConfigError(f"{where}: [[segment]] {i + 1} needs {exc.args[0]} "
                              "(length [m], inner_diameter [m], U [W/(m K)])") from None
    return out


def load(path) -> PipeRecording:
    """Read a pipe recording directory; ConfigError naming the file and the fix for what is missing."""
    d = Path(path)
    cols, decl = d / "columns.toml", d / "pipe.toml"
    for f, what in ((cols, "columns file"), (decl, "pipe declaration")):
        if not f.exists():
            raise ConfigError(f"{f}: no {what}; a pipe recording is a directory with recording.csv, columns.toml "
                              "and pipe.toml (see profiles/recordings/pipes/ULg151202/)")
    try:
        doc = tomllib.loads(decl.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{decl}: not valid TOML: {exc}") from None
    pipe = doc.get("pipe", {})
    segs = _segments(doc, decl)
    rec = read_recording(d)
    t = np.asarray(rec.time, dtype=float)
    csv = d / "recording.csv"
    inlet, outlet = pipe.get("inlet", "pipe.T_in"), pipe.get("outlet", "pipe.T_out")
    T_in = _filled(_signal(rec, inlet, "degC", cols, "inlet water temperature"), t, csv,
                   f"inlet temperature ({inlet})", "the pipe's inlet must be measured throughout")
    T_out = _signal(rec, outlet, "degC", cols, "outlet water temperature")
    if not np.isfinite(T_out).any():
        raise ConfigError(f"{csv}: the outlet temperature ({outlet}) is empty or all NaN: nothing to compare")
    flows = {}
    for sig in sorted({s for seg in segs for s in seg.flow}):
        v = _signal(rec, sig, "kg/s", cols, "mass flow")
        if not np.any(np.isfinite(v) & (v != 0.0)):
            raise ConfigError(f"{csv}: the flow {sig} is all zero or NaN: the replay needs the measured flow "
                              f"through the pipe (check the column mapped to {sig} in {cols} and its unit)")
        flows[sig] = _filled(v, t, csv, f"flow {sig}", "")
    T_env_decl = pipe.get("T_env")
    env = _signal(rec, pipe.get("T_env_signal", "pipe.T_env"), "degC", cols, "ambient temperature", required=False)
    if env is None:
        if T_env_decl is None:
            raise ConfigError(f"{decl}: [pipe] needs T_env (degC) or T_env_signal, the pipe's surroundings")
        env = np.full(len(t), float(T_env_decl))
    ref = None
    if (d / "modelica_reference.csv").exists():
        r = np.loadtxt(d / "modelica_reference.csv", delimiter=",", skiprows=1, ndmin=2)
        ref = (r[:, 0], r[:, 1])
    return PipeRecording(d, t, T_in, T_out, _filled(env, t, csv, "ambient temperature", ""), flows, segs,
                         pipe.get("T_init"), T_env_decl, ref, list(rec.warnings) if hasattr(rec, "warnings") else [])


def _pipes(rec: PipeRecording, o: Options, T0: float) -> list:
    C_total = sum(s.C_steel for s in rec.segments)
    out = []
    for s in rec.segments:
        share = s.C_steel / C_total if C_total > 0 else 1.0 / len(rec.segments)
        kw = {}
        if o.C_wall > 0.0:
            kw.update(C_wall=o.C_wall * share, wall_share_b=o.wall_share_b)
        if o.dispersion > 0.0:
            kw.update(dispersion=o.dispersion)
        out.append(Pipe(s.length, s.diameter, s.U * o.U_factor, T0, **kw))
    return out


def replay(rec: PipeRecording, o: Options = Options()) -> np.ndarray:
    """The modelled outlet temperature at each sample time (inputs linear between samples)."""
    T0 = rec.T_init if rec.T_init is not None else float(rec.T_out[np.isfinite(rec.T_out)][0])
    pipes = _pipes(rec, o, T0)
    flows = [rec.flow(s) * o.flow_factor for s in rec.segments]
    t, n = rec.time, len(rec.time)
    out = np.empty(n)
    out[0] = T0
    last = T0
    for k in range(n - 1):
        dt = t[k + 1] - t[k]
        sub = max(1, int(math.ceil(dt / MAX_STEP)))
        h = dt / sub
        M_out = H_out = 0.0
        for j in range(sub):
            w = (j + 0.5) / sub                       # the sub-step's midpoint between the samples
            T = rec.T_in[k] + w * (rec.T_in[k + 1] - rec.T_in[k])
            env = rec.T_env[k] + w * (rec.T_env[k + 1] - rec.T_env[k]) + o.T_env_offset
            for p, f in zip(pipes, flows):
                p.lose(h, env)
                m = (f[k] + w * (f[k + 1] - f[k])) * h
                if m > 0.0:
                    m, H = p.push(m, T)
                    T = H / (CP * m)
                else:
                    T = p.outlet(+1)
            if m > 0.0:
                M_out, H_out = M_out + m, H_out + m * T
        last = H_out / M_out if M_out > 0.0 else pipes[-1].outlet(+1)
        out[k + 1] = last
    return _sensor(out, t, o.sensor_tau)


def _sensor(T: np.ndarray, t: np.ndarray, tau: float) -> np.ndarray:
    """First-order lag of the outlet sensor (exact for an input linear between samples)."""
    if tau <= 0.0:
        return T
    y = np.empty_like(T)
    y[0] = T[0]
    for k in range(len(T) - 1):
        dt = t[k + 1] - t[k]
        a = math.exp(-dt / tau)
        b = (1.0 - a) * tau / dt if dt > 0 else 1.0   # response to the ramp from T[k] to T[k+1]
        y[k + 1] = a * y[k] + (b - a) * T[k] + (1.0 - b) * T[k + 1]
    return y
