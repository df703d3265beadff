"""What every stage of the diagnosis shares: measured signals, windows, operating modes, costs."""
from __future__ import annotations

import dataclasses
import functools
from dataclasses import dataclass, field

import numpy as np

from ..errors import DataError
from . import roles as roles_mod
from .pipe_sensor import scored_mask
from .requirements import comparable

# normalisation of residuals per unit, so that one cost adds temperatures, flows and powers
SCALE = {"degC": 1.0, "kg/s": 0.02, "W": 500.0}
# a mismatch: a held-out residual above MISMATCH_TOL x scale + NOISE_SIGMAS x the signal's noise
# (Context.limit; labsim's no-effect case, chosen there: 0.3 K, 6 g/s, 150 W)
MISMATCH_TOL = 0.3
NOISE_SIGMAS = 3.0

#: the states of each generator (roles.py: its command and the value above which it runs) the
#: training window must hold where the recording has them (MODE_MIN_S of each, when the recording
#: holds twice that)
MODE_MIN_S = 1800.0


def covering_split(t, data, t_split: float, t_max: float, generators) -> float:
    """The end of the training window: t_split, moved later (up to t_max) to the end of the first
    standstill or run of a generator that the training window lacks and the rest of the recording
    holds. Why: a candidate acting in that state (an idle CHP that keeps flowing) has nothing to be
    fitted on otherwise. rigsim's idle_flow_large (realisation 2): its CHP ran through the two
    training days and stood five times after; fitted on no standstill, the idle flow came out 0.
    generators: the house's (roles.Roles.generators)."""
    dt = np.diff(t, append=t[-1])
    for unit in generators:
        if unit.command not in data:
            continue
        runs = unit.runs(data)
        for state in (runs, ~runs):
            if dt[state & (t <= t_split)].sum() >= MODE_MIN_S or dt[state].sum() < 2 * MODE_MIN_S:
                continue
            later = np.flatnonzero(state & (t > t_split))
            if not later.size:
                continue
            # the end of the first block of this state after the split
            gaps = np.flatnonzero(np.diff(later) > 1)
            end = t[later[gaps[0]] if gaps.size else later[-1]]
            t_split = max(t_split, min(float(end), t_max))
    return t_split


@dataclass(frozen=True)
class Context:
    """The recording as every stage sees it. Built once from the recording (build); a stage that
    learns something the later ones judge by (the nominal replay, the unit modes masked) returns
    a new Context (dataclasses.replace, with_baseline, unit_modes.apply), never changes one."""
    rec: object
    measured: list
    train: np.ndarray        # bool mask of samples used for fitting
    held: np.ndarray         # bool mask of held-out samples
    meas: np.ndarray         # [n, n_measured] measured values (NaN = missing)
    ok: np.ndarray           # [n, n_measured] finite & valid
    scale: np.ndarray
    noise: np.ndarray        # estimated white-noise sigma per measured signal
    flags: dict = field(default_factory=dict)
    cols: np.ndarray | None = None  # catalogue indices of the measured signals
    t_split: float = float("nan")   # end of the training window [s]
    roles: object = None            # roles.Roles of the replayed house (its modes: flags)
    # the baseline (with_baseline): the nominal replay (replay.Replay: all catalogue signals, its
    # pipe and storage-sensor reading fits), the measured columns every candidate is judged on
    # (the nominal's, or the model a further effect goes on top of: forward.py), the subsystem
    # replayed alone {instances, signals}, the signals of a subsystem calibrated alone on them,
    # and override key -> (lo, hi) the nominal re-fit may take
    nominal: object = None
    nominal_sim: np.ndarray | None = None
    alone: tuple = ()   # each {instances, signals}: a subsystem replayed alone
    calibrated: tuple = ()
    nominal_ranges: dict = field(default_factory=dict)
    calibration: dict = field(default_factory=dict)  # override key -> the value every replay starts from
    # storage sensors the nominal replay cannot represent (unrepresented.find): sensor -> its entry
    unrepresented: dict = field(default_factory=dict)

    @classmethod
    def build(cls, rec, train_days: float = 2.0, warmup_h: float = 1.0, simulated=None, roles=None):
        """simulated: the signals the replay computes (Replayer.simulated; None: all); roles: the
        replayed house's (Replayer.roles; None: house 1's)."""
        roles = roles or roles_mod.of()
        measured = [s for s in comparable(roles.house) if rec.has(s) and (simulated is None or s in simulated)]
        t = rec.time
        n = len(t)
        valid = rec.valid if rec.valid is not None else np.ones(n, bool)
        valid = valid & (t >= t[0] + warmup_h * 3600.0)
        span = t[-1] - t[0]
        t_split = covering_split(t, rec.data, t[0] + min(train_days * 86400.0, 0.4 * span), t[0] + 0.5 * span,
                                 roles.generators)
        train = valid & (t <= t_split)
        held = valid & (t > t_split)
        h_train = (t_split - t[0]) / 3600.0 - warmup_h
        h_held = (t[-1] - t_split) / 3600.0
        if h_train < 2.0 or h_held < 3.0 or train.sum() < 10 or held.sum() < 10:
            raise DataError(f"{rec.source}: the recording spans {span / 3600.0:.1f} h: too short for a "
                            f"training and a held-out window (after a {warmup_h:g} h warm-up it needs >= 2 h "
                            f"to train and >= 3 h held out; it has {max(h_train, 0.0):.1f} h and {h_held:.1f} h); "
                            "record longer or give a smaller --train-days")
        meas = np.column_stack([rec.data[s] for s in measured])
        ok = np.isfinite(meas) & valid[:, None]
        # a pipe sensor's reading is modelled while its branch stands (pipe_sensor.py); the
        # samples where its branch starts or stops are not scored
        ok &= scored_mask(rec, measured, roles.pipes)
        scale = np.array([SCALE.get(roles.catalogue.signal(s).unit, 1.0) for s in measured])
        noise = np.zeros(len(measured))
        for j in range(len(measured)):
            d = np.diff(meas[:, j][np.isfinite(meas[:, j])])
            if d.size > 10:
                noise[j] = 1.4826 * np.median(np.abs(d - np.median(d))) / np.sqrt(2.0)
        return cls(rec, measured, train, held, meas, ok, scale, noise, roles.flags(rec.data),
                   cols=np.array([roles.catalogue.index(s) for s in measured]), t_split=t_split, roles=roles)

    def with_baseline(self, nominal, alone: tuple, calibrated: tuple, nominal_ranges: dict,
                      calibration: dict | None = None) -> "Context":
        """This context judged against the nominal replay `nominal` (a replay.Replay)."""
        return dataclasses.replace(self, nominal=nominal, nominal_sim=nominal.rows[:, self.cols], alone=alone,
                                   calibrated=tuple(calibrated), nominal_ranges=dict(nominal_ranges),
                                   calibration=dict(calibration or {}))

    @property
    def heights(self) -> dict:
        """Storage sensor -> its place fitted in the nominal replay (sensor_height.HeightFit)."""
        return self.nominal.heights if self.nominal is not None else {}

    # --- modes -----------------------------------------------------------------------------
    @property
    def modes(self) -> dict:
        """Mode flag -> its words in the report."""
        return self.roles.modes()

    @functools.cached_property
    def states(self) -> dict:
        """Operating state -> mask: the mode flags and each single unit's off-state (Roles.states).
        Cached: a frozen context's flags never change (a stage that masks modes makes a new one)."""
        return self.roles.states(self.flags) if self.roles is not None else dict(self.flags)

    def unit(self, signal: str) -> str:
        """A signal's unit (the replayed house's catalogue)."""
        return self.roles.catalogue.signal(signal).unit

    def index(self, signal: str) -> int:
        """A signal's column in the replay's rows (the replayed house's catalogue)."""
        return self.roles.catalogue.index(signal)

    def mode_mask(self, name: str) -> np.ndarray:
        """The samples in mode `name` (Roles.modes); none in a mode the house cannot be in (a
        mode of units it lacks: house 5 has no idle-CHP mode)."""
        if name not in self.flags:
            return np.zeros(len(self.rec.time), dtype=bool)
        return self.flags[name]

    def mode_share(self, name: str) -> float:
        return float(np.mean(self.mode_mask(name)))

    # --- costs -----------------------------------------------------------------------------
    def residual(self, sim_meas: np.ndarray) -> np.ndarray:
        """measured - simulated, [n, n_measured], NaN where not scored."""
        r = self.meas[: len(sim_meas)] - sim_meas
        return np.where(self.ok[: len(sim_meas)], r, np.nan)

    def per_signal_mse(self, sim_meas: np.ndarray, mask: np.ndarray) -> np.ndarray:
        r = self.residual(sim_meas)
        m = mask[: len(r)]
        with np.errstate(invalid="ignore"):
            return np.nanmean(r[m] ** 2, axis=0) if m.any() else np.full(r.shape[1], np.nan)

    def cost(self, sim_meas: np.ndarray, mask: np.ndarray, per_signal: np.ndarray | None = None,
             signals=()) -> float:
        """Mean over signals (those of `signals` that are measured, when given) of the normalised
        mean squared residual."""
        mse = self.per_signal_mse(sim_meas, mask) if per_signal is None else per_signal
        v = mse / self.scale ** 2
        idx = [self.measured.index(s) for s in signals if s in self.measured]
        return float(np.nanmean(v[idx] if idx else v))

    def weighted_residuals(self, sim_meas: np.ndarray, mask: np.ndarray) -> np.ndarray:
        """The residuals whose sum of squares is cost(sim_meas, mask): each scored sample of
        `mask` over its signal's scale and the square root of (its signal's scored samples x the
        signals scored), 0 where not scored; one fixed layout for every replay of a window."""
        r = self.residual(sim_meas)[mask[: len(sim_meas)]] / self.scale
        n = np.sum(np.isfinite(r), axis=0)
        w = np.where(n > 0, 1.0 / np.sqrt(np.maximum(n, 1) * max(int(np.sum(n > 0)), 1)), 0.0)
        return np.nan_to_num(r * w).ravel()

    def limit(self, j, tol: float = None) -> float | np.ndarray:
        """The one mismatch limit of signal(s) j, in its unit: what a correct replay may leave
        (tol of its scale, MISMATCH_TOL unless given: replay timing, an independent plant's
        structure; 0 for a subsystem calibrated alone on that very signal) plus NOISE_SIGMAS of
        its noise."""
        return (MISMATCH_TOL if tol is None else tol) * self.scale[j] + NOISE_SIGMAS * self.noise[j]

    def noise_cost(self) -> float:
        return float(np.nanmean((self.noise / self.scale) ** 2))

    def n_eff(self, mask: np.ndarray) -> float:
        """Effective independent samples of a window (residuals are strongly autocorrelated:
        counted as one per 30 min and signal group)."""
        t = self.rec.time[mask]
        if t.size < 2:
            return 1.0
        return max(2.0, (t[-1] - t[0]) / 1800.0)
