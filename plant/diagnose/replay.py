"""Replay a recording through the twin: recorded commands in, simulated signals out at the samples.

The twin runs with controller="external": the four supervisory commands and the two heating-
circuit set-points come from the recording (the same generator set-points in simulation and
experiment, so control decisions cannot diverge). A recording that measures the heating circuit
and the hot water taken is replayed on a cut (cut.py: those measured boundaries instead of the
twin's building and DHW profiles, the mixing station alone between its measured interfaces);
otherwise weather, occupancy, household electricity and the DHW draw come from the twin's own
profiles for the recording's start date, and a recording that carries them is checked against
the profiles (a warning when they differ).

Between two samples the command may have changed anywhere in the interval: when it differs, the
old value is held for the first half of the interval and the new one for the second half (an
unbiased edge time, halving the timing error of a plain sample-and-hold). A measured boundary is
bound the same way: a sample holds from the midpoint before it to the midpoint after it.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field

import numpy as np

from ..errors import ConfigError
from . import cut as cut_mod
from . import emitter as emitter_mod
from . import pipe_sensor, sensor_height
from . import roles as roles_mod
from .requirements import BOUNDARY, profile_differs

@dataclass(frozen=True)
class Replay:
    """One run of the replayed twin: rows [n_samples, n_signals] in catalogue order, the pipe sensors'
    fits (flow signal -> pipe_sensor fit) and the storage sensors' places (-> sensor_height.HeightFit)."""
    rows: np.ndarray
    pipe: dict = field(default_factory=dict)
    heights: dict = field(default_factory=dict)


@dataclass(frozen=True)
class PlantRoom:
    """What the stagnant pipes cool toward [degC], and where that value comes from."""
    T: float
    source: str


MEMO_BYTES = 256 * 2 ** 20  # plant rows kept for repeated drives (about 30 seven-day replays)
ALONE_KEPT = 64  # subsystem replays kept (a few samples' columns each)
MIN_CALIBRATION_SAMPLES = 30  # flowing samples a subsystem calibrated alone needs in the training window


class Drives:
    """The plant rows of earlier drives, by key, within a memory budget (MEMO_BYTES). When full,
    the oldest entry never asked for again goes first: a candidate's nominal point is asked for
    once per candidate, a hundred drives apart, and is worth keeping over a grid point of one
    search."""

    def __init__(self, budget: int | None = None):
        self.budget = MEMO_BYTES if budget is None else budget
        self._rows: dict = {}   # key -> rows, in insertion (age) order
        self._hits: dict = {}
        self.used = 0

    def get(self, key):
        rows = self._rows.get(key)
        if rows is not None:
            self._hits[key] += 1
        return rows

    def put(self, key, rows: np.ndarray) -> None:
        rows.setflags(write=False)  # shared by every run that asks again: nobody may change it
        while self._rows and self.used + rows.nbytes > self.budget:
            old = next((k for k in self._rows if not self._hits[k]), next(iter(self._rows)))
            self.used -= self._rows.pop(old).nbytes
            del self._hits[old]
        if rows.nbytes <= self.budget:
            self._rows[key] = rows
            self._hits[key] = 0
            self.used += rows.nbytes


class Replayer:
    """Drive the twin with a recording's commands (and, on a cut, its measured boundaries);
    `run(overrides)` -> a Replay: simulated rows at the samples, in house 1's catalogue order (NaN
    for the signals the replayed plant does not simulate; a bound boundary column holds the
    recording), with the sensor reading models fitted to it.

    A calibration never changes a replayer: it returns values, and `with_calibration` gives the
    replayer every later run uses (base overrides, the instances calibrated alone, the emitter's
    element count, the end of the training window)."""

    def __init__(self, rec, house: str = "house1", init_from_sensors: bool = True, require_cut: bool = False,
                 generators=()):
        self.rec = rec
        self.house_name = house
        self.init_from_sensors = init_from_sensors
        self.t = rec.time
        self.cut, self.circuit = cut_mod.select(rec, house, required=require_cut, generators=generators)
        self.emitter = cut_mod.emitter_alone(rec, self.cut, house)
        # the heating circuit by role (its station, coupling point, emitter, zone): emitter.of
        self.heating = emitter_mod.of(house)
        removed = set(self.cut.removes) if self.cut else set()
        self.removed = removed
        # the instances the cut removed that are replayed alone between their measured interfaces
        self.alone_instances = (({self.heating.station} if self.circuit else set())
                                | ({self.heating.emitter} if self.emitter else set()))
        # what the replay loads (a derived cut's file) and what the report calls it
        self.plant_name = str(self.cut.path()) if self.cut else house
        self.plant_label = self.cut.label if self.cut else str(house)
        self.roles = roles_mod.of(house)
        # a loop whose recorded command switches faster than the scan (Roles.unfollowed) runs on the
        # twin's own control at the plant's step: its command held between samples would give it
        # the heat of whole scans it ran for seconds (rigsim house 3's June collector: x 0.32 for
        # 0.6 replayed, x 0.47 on its own control)
        self.unfollowed = self.roles.unfollowed(rec.data)
        self.commands = [c for c in self.roles.replayed(rec) if c.split(".", 1)[0] not in removed]
        bound = dict(self.cut.bindings) if self.cut else {}
        self.names = self.commands + list(bound)
        self.cmd = np.column_stack([rec.data[c] for c in self.commands] + [rec.data[s] for s in bound.values()])
        self.bound = bound
        self.notes: list[str] = []
        if self.cut:
            self.notes.append(f"replayed on the cut {self.plant_label}: {self.cut.why}"
                              + ("; the mixing station replayed alone between its measured interfaces"
                                 if self.circuit else "")
                              + (f"; the {self.heating.noun} replayed alone (measured flow, supply and room "
                                 "-> return)" if self.emitter else "")
                              + f"; the cut's house file (derived from {house}): {self.plant_name}")
        self._checked = False
        # the plant's rows by (overrides, samples), shared by the replayers with_calibration makes:
        # a third of a diagnosis's drives repeat one already made (each candidate starts at the
        # nominal point; the re-fit's descents return to earlier values)
        self._drives = Drives()
        self._subsystems: dict = {}  # the same for the subsystems replayed alone (_alone)
        # calibrated values (with_calibration): applied to every run, a run's own overrides over them
        self.base: dict = {}
        # where the lab's storage sensors and ports are (columns file): every run starts from them
        self.lab = {**(rec.sensor_overrides() if hasattr(rec, "sensor_overrides") else {}), **self._lab_ports()}
        # the end of the training window: the pipe sensors' cooling and the storage sensors' places
        # are fitted up to it (pipe_sensor.py, sensor_height.py); the pipe sensors read as
        # simulated only where the nominal replay's fits do (pipe_sensor.apply's nominal)
        self.t_train: float | None = None
        self.pipe_nominal: dict = {}
        # the emitter alone's element count (until calibrated emitter.OWN, its kind's kernel) and
        # the instances calibrated on their own subsystem: the nominal re-fit leaves those alone
        self.emitter_elements = emitter_mod.OWN
        self.calibrated: frozenset = frozenset()
        self._layout()
        self.room = self._plant_room()
        self.heights = self.tank_heights()

    def with_calibration(self, base: dict | None = None, calibrated=(), emitter_elements: int | None = None,
                         t_train: float | None = None, pipe_nominal: dict | None = None) -> "Replayer":
        """A replayer like this one whose runs start from `base` on top of this one's, with the
        instances `calibrated` alone added (and the emitter's element count, the end of the
        training window, the nominal replay's pipe fits, where given)."""
        out = copy.copy(self)
        out.pipe_nominal = {**self.pipe_nominal, **(pipe_nominal or {})}
        out.base = {**self.base, **(base or {})}
        out.calibrated = self.calibrated | frozenset(calibrated)
        if emitter_elements is not None:
            out.emitter_elements = emitter_elements
        if t_train is not None:
            out.t_train = t_train
        return out

    def _layout(self) -> None:
        from ..compiler import catalogue_of

        cat = catalogue_of(self.plant_name)
        self._src, self._dst = [], []
        # nor is a bound signal's recorded counterpart (boiler.T_sup follows T_sup_measured)
        inputs = set(self.bound) | set(self.bound.values())
        simulated = []
        for s in cat:
            if s.name in self.roles.catalogue:
                self._src.append(s.index)
                self._dst.append(self.roles.catalogue.index(s.name))
                if s.name not in inputs and s.causality == "output":
                    simulated.append(s.name)
        if self.circuit:
            simulated += list(self.heating.station_outputs)
        if self.emitter:
            simulated += list(self.heating.emitter_outputs)
        self.simulated = set(simulated)  # catalogue names the replay computes (the others are not compared)

    def _lab_ports(self) -> dict:
        """Overrides that put the storage's ports where the recording's [ports] says: the
        coupling point's storage_top / storage_bottom [m] from the relative heights."""
        from ..declaration import load

        ports = getattr(self.rec, "ports", None) or {}
        if not ports:
            return {}
        spec = load(self.plant_name)
        out = {}
        for name, rel in ports.items():
            points = sensor_height.points_of(spec, name)
            if not points or name not in spec.instances:
                raise ConfigError(f"[ports] {name}: {self.plant_label} has no coupling point whose storage is "
                                  f"{name!r}; ports can be declared for "
                                  + (", ".join(sorted({i.options["storage"] for i in spec.instances.values()
                                                       if "storage_top" in i.options})) or "no storage"))
            H = float(spec.instances[name].params.height)
            for inst in points:
                out[f"{inst.name}.storage_top"] = rel["top"] * H
                out[f"{inst.name}.storage_bottom"] = rel["bottom"] * H
                self.notes.append(f"{name}: ports at {rel['top'] * H:.3f} m and {rel['bottom'] * H:.3f} m from the "
                                  f"columns file's [ports] (house file: {inst.options['storage_top']} m and "
                                  f"{inst.options['storage_bottom']} m)")
        return out

    def tank_heights(self) -> dict:
        """Every storage of the replayed plant by name -> sensor_height.Tank (its ports where the
        columns file's [ports] put them)."""
        from ..declaration import load

        return sensor_height.tanks(load(self.plant_name), self.lab)

    def _plant_room(self) -> PlantRoom:
        """(what the stagnant pipes cool toward, where it comes from): read off the recording's
        long standstills (pipe_sensor.plant_room), else the replayed house's storage.T_env."""
        from ..declaration import load

        room = pipe_sensor.plant_room(self.rec, self.roles.pipes)
        if room is not None:
            return PlantRoom(room, "recording (pipes after 6 h of standstill)")
        inst = load(self.plant_name).instances.get("storage")
        if inst is not None and hasattr(inst.params, "T_env"):
            return PlantRoom(float(inst.params.T_env), "house file (storage.T_env)")
        return PlantRoom(pipe_sensor.T_PLANT_ROOM_DEFAULT, "default")

    def instances(self) -> set:
        """Instances a run's overrides may address: the replayed plant's, and the mixing
        station's when it is replayed alone."""
        from ..declaration import load

        return set(load(self.plant_name).instances) | self.alone_instances

    def _init_storage(self, house) -> None:
        for comp in self.heights:  # the replayed plant's storages
            names = [f"{comp}.T_sensor_{i}" for i in range(1, 11)]
            if not all(self.rec.has(n) for n in names):
                continue
            meas = np.array([self.rec.data[n][0] for n in names])
            if not np.all(np.isfinite(meas)):
                continue
            sim = np.array([house.get(n) for n in names])
            if np.max(np.abs(meas - sim)) < 0.5:
                continue
            n = house.state(comp).shape[0]
            z_layer = 1.0 - (np.arange(n) + 0.5) / n  # layer 0 = top
            z_sens = (np.arange(10) + 0.5) / 10.0
            house.set_state(comp, np.interp(z_layer, z_sens, meas))
            if not self._checked:
                self.notes.append(f"{comp}: initial layer temperatures set from the first recorded sensor "
                                  f"values (twin default differed by up to {np.max(np.abs(meas - sim)):.1f} K)")

    def _plant(self, ov: dict, n: int) -> np.ndarray:
        from ..house import load_house

        key = (tuple(sorted((k, repr(v)) for k, v in ov.items())), n)
        hit = self._drives.get(key)
        if hit is not None:
            return hit
        house = load_house(self.plant_name, start=self.rec.start, controller="external", overrides=ov or None)
        if self.init_from_sensors:
            for name, value in zip(self.names, self.cmd[0]):
                if np.isfinite(value):
                    house.set(name, value)
            self._init_storage(house)
        # commands and measured boundaries alike: a sample holds from the midpoints around it
        rows = house.drive(self.t[:n], self.names, self.cmd[:n])[:, self._src]
        self._drives.put(key, rows)
        return rows

    def _alone(self, prefix: str, sub_ov: dict, n: int, replay_fn, *args) -> dict:
        """A subsystem replayed alone (replay_fn) with the overrides starting with `prefix`; the
        same overrides give the same values, so most runs (a candidate elsewhere) reuse them."""
        own = {k: v for k, v in sub_ov.items() if k.startswith(prefix)}
        key = (prefix, tuple(sorted((k, repr(v)) for k, v in own.items())), n, args)
        if key not in self._subsystems:
            if len(self._subsystems) >= ALONE_KEPT:
                del self._subsystems[next(iter(self._subsystems))]
            self._subsystems[key] = replay_fn(self.rec, self.house_name, own, n, *args)
        return self._subsystems[key]

    def run(self, overrides: dict | None = None, until: float | None = None) -> Replay:
        """The twin replayed at the recording's sample times (up to `until`), from the base
        overrides and `overrides` on top."""
        ov = {**self.lab, **self.base, **(overrides or {})}
        n = len(self.t) if until is None else int(np.searchsorted(self.t, until, side="right"))
        plant_ov = {k: v for k, v in ov.items() if k.split(".", 1)[0] not in self.removed}
        sub_ov = {k: v for k, v in ov.items() if k.split(".", 1)[0] in self.removed}
        lost = [k for k in sub_ov if k.split(".", 1)[0] not in self.alone_instances]
        if lost:
            raise ConfigError(f"replay on {self.plant_label}: override(s) {', '.join(lost)} address instances the "
                              f"cut replaces by measured boundaries ({', '.join(sorted(self.removed))})")
        rows_plant = self._plant(plant_ov, n)
        out = np.full((n, len(self.roles.catalogue)), np.nan)
        out[:, self._dst] = rows_plant
        for inp, sig in self.bound.items():
            out[:, self.roles.catalogue.index(sig)] = self.rec.data[sig][:n]
        if self.circuit:
            for sig, v in self._alone(f"{self.heating.station}.", sub_ov, n, cut_mod.replay_circuit).items():
                out[:, self.roles.catalogue.index(sig)] = v
        if self.emitter:
            for sig, v in self._alone(f"{self.heating.emitter}.", sub_ov, n, emitter_mod.replay,
                                      self.emitter_elements).items():
                out[:, self.roles.catalogue.index(sig)] = v
        cols = {s: self.roles.catalogue.index(s) for s in self.simulated | set(self.bound.values())}
        t_fit = None if self.t_train is None else self.t_train if until is None else min(self.t_train, until)
        pipe = pipe_sensor.apply(self.rec, out, cols, n, self.room.T, t_fit, self.roles.pipes, self.pipe_nominal)
        tanks = {k: t._replace(layers=int(ov.get(f"{k}.n_layers", t.layers))) for k, t in self.heights.items()}
        heights = sensor_height.apply(self.rec, out, cols, n, tanks, t_fit)  # (a scheme's layers)
        self._checked = True
        return Replay(out, pipe, heights)

    def circuit_flowing(self, settled: bool = False) -> np.ndarray:
        """The samples at which the heating circuit flows (settled: and flowed the sample before,
        so the emitter's return is its own and not the stagnant pipe's)."""
        flow = np.nan_to_num(self.rec.data[self.heating.emitter_inputs[0]]) > pipe_sensor.FLOWING
        return flow & np.roll(flow, 1) if settled else flow

    def _circuit_training(self, train: np.ndarray, signal: str, what: str, keeps: str):
        """The training samples at which the circuit flows (and flowed the sample before) and
        `signal` is recorded -> (mask, None), or (None, the report entry saying why `what` is not
        calibrated: too few of them)."""
        mask = train & self.circuit_flowing(settled=True) & np.isfinite(self.rec.data[signal])
        if mask.sum() >= MIN_CALIBRATION_SAMPLES:
            return mask, None
        why = (f"the heating circuit flows at {int(mask.sum())} recorded samples of the training window "
               f"(< {MIN_CALIBRATION_SAMPLES}): {keeps}")
        self.notes.append(f"{what} not calibrated: {why}")
        return None, {"calibrated": False, "why": why}

    def calibrate_emitter(self, train: np.ndarray) -> dict | None:
        """Calibrate the emitter replayed alone on the recorded return over the training samples
        at which the circuit flows (emitter.calibrate). -> report entry ({calibrated, values,
        elements, ...}; with_calibration applies it) or None without an emitter alone."""
        if not self.emitter:
            return None
        mask, skipped = self._circuit_training(
            train, self.heating.emitter_outputs[0], f"{self.heating.noun} alone",
            f"the {self.heating.noun} alone runs the house file's model and values")
        if skipped:
            return skipped
        return {**emitter_mod.calibrate(self.rec, self.house_name, mask), "calibrated": True}

    def calibrate_mixer(self, train: np.ndarray, overrides: dict | None = None) -> dict | None:
        """Calibrate the mixing station replayed alone on the recorded supply after mixing over
        the training samples at which the circuit flows (cut.calibrate_mixer; a candidate's
        `overrides` held). -> report entry ({calibrated, values, ...}) or None without one."""
        if not self.circuit:
            return None
        mask, skipped = self._circuit_training(train, self.heating.station_outputs[0], "mixing station alone",
                                               "the mixing station keeps the house file's actuator and gain")
        if skipped:
            return skipped
        return {**cut_mod.calibrate_mixer(self.rec, self.house_name, mask, overrides), "calibrated": True}

    def emitter_return(self, values: dict, elements: int | None, pipe: dict) -> np.ndarray:
        """The compared return of the emitter alone with `values` (its overrides) and `elements`
        (None: the calibrated count) over the whole recording, read through the pipe-sensor fits
        `pipe` (a Replay's)."""
        h = self.heating
        ov = {k: v for k, v in {**self.base, **values}.items() if k.startswith(f"{h.emitter}.")}
        y = emitter_mod.replay(self.rec, self.house_name, ov, len(self.t),
                               self.emitter_elements if elements is None else elements)[h.emitter_outputs[0]]
        flow = h.emitter_inputs[0]
        fit = pipe.get(flow, pipe_sensor.AS_SIMULATED_FIT)
        return pipe_sensor.cooled(self.t, y, self.rec.data[flow], fit, self.room.T)

    def refit_emitter(self, transform, mask: np.ndarray) -> tuple:
        """The emitter alone re-fitted with a sensor candidate's `transform` on its return
        (jointly, as the nominal re-fit is with a plant candidate): its calibrated parameters,
        and the element count next to the calibrated one. -> (values, elements)."""
        start = {k: v for k, v in self.base.items() if k in self.heating.bounds}
        near = [N for N in self.heating.elements if abs(N - self.emitter_elements) <= 1]
        fits = {N: emitter_mod.fit(self.rec, self.house_name, mask & self.circuit_flowing(settled=True), N, start,
                                   transform) for N in near}
        N = min(fits, key=lambda q: fits[q][1])
        return fits[N][0], N

    def boundary_check(self, rows: np.ndarray) -> list[str]:
        warnings = []
        for b in BOUNDARY:
            if not self.rec.has(b):
                continue
            m = self.rec.data[b][: len(rows)]
            sim = rows[:, self.roles.catalogue.index(b)]
            ok = np.isfinite(m) & np.isfinite(sim)
            if not ok.any():
                continue
            err = float(np.sqrt(np.mean((m[ok] - sim[ok]) ** 2)))
            scale = max(1e-9, float(np.std(sim[ok])))
            if profile_differs(err, scale, b):
                warnings.append(f"{b}: the recording differs from the twin's profile for {self.rec.start} "
                                f"(RMS {err:.3g}); the twin uses its own profiles - check the start date")
        return warnings
