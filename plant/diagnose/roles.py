"""What the diagnosis needs of a house, read from its declaration and its kinds, never from
instance names: the commands a recording replays (what the house's controllers write), the
units whose operating mode a recording shows (a kind's RUN: the command that starts it and the
value above which it runs), the running state a lab measures (RAN), the pipe sensors on each
unit's branch (PIPES), the commands a measured output may stand in for (SUBSTITUTES), the
outputs no lab measures (UNMEASURED) and the inputs a kind's own control writes, which a
recording drives where it carries them (COMMANDS). plant/component.py declares those attributes; a kind that
sets them takes part, whatever the house calls its instance.

The operating modes the diagnosis localises a mismatch in are built from the units: each
generator on and (where its coupling point may pass an idle flow through it) off, any heating
circuit's pump on, any charging coil's pump on, each idle-capable generator off while the
heating runs, and each pair of generators on together.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from itertools import combinations

import numpy as np

from ..kinds import KINDS


MIN_PULSES = 3   # one or two single-sample runs may be a unit's real short run, three are a pattern


@dataclass(frozen=True)
class Unit:
    name: str                 # the instance
    noun: str                 # what the report calls it (the kind's noun, the name when two share it)
    command: str              # the recorded command that starts it
    on_above: float           # ... and the value above which it runs
    flow: str | None          # its branch's flow signal (the pipe sensors' evidence)
    pipes: tuple = ()         # pipe sensors on its branch
    ran: tuple | None = None  # (measured output, value above which it ran)
    idles: bool = False       # its coupling point may pass an idle flow through it
    counter: str | None = None  # its delivered-heat counter (a kind's COUNTER)

    def runs(self, data) -> np.ndarray:
        """Samples at which the recording commands the unit to run."""
        return np.nan_to_num(data[self.command]) > self.on_above


@dataclass(frozen=True)
class Roles:
    house: str
    generators: tuple         # Unit, in declaration order
    circuits: tuple           # heating circuits (a pump the recording commands)
    chargers: tuple           # charging coils' pumps
    commands: tuple           # inputs the house's controllers write, in their instances' order
    substitutes: dict         # command -> the output a recording may give instead
    unmeasured: frozenset     # outputs never compared
    catalogue: object = None  # the house's SignalCatalogue: the replay's columns, every signal's unit
    buffer: tuple | None = None  # (storage, volume m3, its sensors): the first storage a coupling point feeds
    subsystems: dict | None = None  # instance -> the subsystem the report localises a mismatch in
    loops: tuple = ()         # other units with a pump and pipe sensors (a solar loop)
    own_commands: tuple = ()  # inputs a kind's own control writes: replayed where recorded (COMMANDS)
    source_pipes: dict = field(default_factory=dict)  # pipe sensor on a unit's source loop -> (its flow,
    #                                                  the unit's command, threshold) (SOURCE_PIPES)

    def subsystem(self, signal: str) -> str:
        return (self.subsystems or {}).get(signal.split(".", 1)[0], "other")

    @cached_property
    def _modes(self) -> tuple:
        """(flag, its words in the report, the units whose state makes it: (name, on?) each), in
        the report's order; the heating and charging pumps are the units `heating` and `dhw`."""
        out = []
        for g in self.generators:
            out.append((f"{g.name}_on", f"{g.noun} on", ((g.name, True),)))
            if g.idles:
                out.append((f"{g.name}_off", f"{g.noun} off", ((g.name, False),)))
        if self.circuits:
            out.append(("heating_on", "heating pump on", (("heating", True),)))
        if self.chargers:
            out.append(("dhw_on", "DHW charging on", (("dhw", True),)))
        if self.circuits:
            out += [(f"{g.name}_off_heating_on", f"{g.noun} off and heating pump on", ((g.name, False), ("heating", True)))
                    for g in self.generators if g.idles]
        out += [(f"{a.name}_on_{b.name}_on", f"{a.noun} and {b.noun} on", ((a.name, True), (b.name, True)))
                for a, b in combinations(self.generators, 2)]
        return tuple(out)

    def modes(self) -> dict:
        """Mode flag -> its words in the report."""
        return {flag: words for flag, words, _ in self._modes}

    def flags(self, data) -> dict:
        """Mode flag -> samples at which the recording's commands put the house in it."""
        on = {g.name: g.runs(data) for g in self.generators}
        for name, units in (("heating", self.circuits), ("dhw", self.chargers)):
            if units:
                on[name] = np.any([u.runs(data) for u in units], axis=0)
        return {flag: np.logical_and.reduce([on[u] if state else ~on[u] for u, state in made])
                for flag, _, made in self._modes}

    def states(self, flags: dict) -> dict:
        """The mode flags (of `flags`) and each unit's off-state the modes lack: the states a
        sensor's own error is the same in (SensorOffset.unlike). A sensor at a port reads the
        port's water only while that unit runs: rigsim house 2's tank sensor 2, at the heat pump's
        lower return, read +2.8 K against the twin with the heat pump on and -3.0 K with it off,
        and the modes had no "heat pump off" to show it."""
        out = dict(flags)
        for flag, _, made in self._modes:
            if len(made) == 1 and made[0][1] and flag.endswith("_on"):
                out.setdefault(flag[:-3] + "_off", ~flags[flag])
        return out

    @property
    def pipes(self) -> dict:
        """Pipe sensor -> (its branch's flow, the command that starts the branch, its threshold)."""
        out = {p: (u.flow, u.command, u.on_above) for u in (*self.generators, *self.circuits, *self.loops)
               for p in u.pipes}
        out.update(self.source_pipes)
        return out

    def unfollowed(self, data) -> dict:
        """Loop (a unit with its own control) -> its number of runs shorter than the recording's
        scan, for each loop that has at least MIN_PULSES of them: recorded command runs that are,
        by the median, one sample long, or, where the recording has the loop's counter, rises of
        it between two samples that both read the command off (runs the scan never saw: the
        twin's own house 3 in January, its collector pump running for seconds at a time, gave
        176 kJ in 2.5 h with the pump off at every sample). It switches faster than the recording
        is scanned, so a replay holding the command between samples cannot follow it (a solar
        station's pump that pulses for seconds while cold loop water cools the collector)."""
        out = {}
        for u in self.loops:
            if u.command not in data:
                continue
            on = u.runs(data)
            edges = np.flatnonzero(np.diff(np.concatenate(([0], on.astype(np.int8), [0]))))
            lengths = edges[1::2] - edges[::2]
            if lengths.size >= MIN_PULSES and np.median(lengths) <= 1:
                out[u.name] = int(lengths.size)
            elif u.counter is not None and u.counter in data:
                # off at both ends and at the sample before: a meter that books a run's last heat
                # one scan late is not a run of its own
                off = ~on[:-1] & ~on[1:] & ~np.concatenate(([False], on[:-2]))
                unseen = int(np.sum((np.diff(np.asarray(data[u.counter], dtype=float)) > 0) & off))
                if unseen >= MIN_PULSES:
                    out[u.name] = unseen
        return out

    def replayed(self, rec) -> tuple:
        """The commands a replay drives from `rec`: its controllers' (all required) and the kinds'
        own controls it recorded, but for loops it cannot follow (unfollowed), whose own control
        runs them."""
        fast = self.unfollowed(rec.data)
        return self.commands + tuple(c for c in self.own_commands
                                     if rec.has(c) and c.split(".", 1)[0] not in fast)

    @property
    def ran(self) -> dict:
        """Unit -> (the output whose recorded value says it ran, the threshold)."""
        return {g.name: g.ran for g in self.generators if g.ran}


@lru_cache(maxsize=32)
def of(house="house1") -> Roles:
    """The roles of `house` (a name or a house file)."""
    from ..compiler import catalogue_of
    from ..declaration import load

    spec = load(house)
    inst = list(spec.instances.values())
    idle = {g for i in inst for g in (i.options.get("idle_flow") or {})}
    nouns = [getattr(KINDS[i.kind], "NOUN", i.name) for i in inst if KINDS[i.kind].role == "generator"]

    def unit(i) -> Unit:
        k = KINDS[i.kind]
        cmd, above = k.RUN
        noun = getattr(k, "NOUN", i.name)
        return Unit(i.name, noun if nouns.count(noun) == 1 else i.name, f"{i.name}.{cmd}", above,
                    f"{i.name}.m_flow" if k.PIPES else None, tuple(f"{i.name}.{p}" for p in k.PIPES),
                    (f"{i.name}.{k.RAN[0]}", k.RAN[1]) if k.RAN else None, i.name in idle,
                    f"{i.name}.{k.COUNTER}" if k.COUNTER else None)

    runs = [i for i in inst if KINDS[i.kind].RUN]
    generators = tuple(unit(i) for i in runs if KINDS[i.kind].role == "generator")
    circuits = tuple(unit(i) for i in runs if KINDS[i.kind].role == "consumer" and KINDS[i.kind].PIPES)
    chargers = tuple(unit(i) for i in runs if KINDS[i.kind].role == "consumer" and not KINDS[i.kind].PIPES)
    loops = tuple(unit(i) for i in runs if KINDS[i.kind].role not in ("generator", "consumer") and KINDS[i.kind].PIPES)
    order = {i.name: n for n, i in enumerate(inst)}
    # a controller the house file switches off (active = 0: the substation's rules in a house run
    # alone) writes nothing a recording must carry; its inputs stay at rest in the replay
    written = [str(s) for i in inst if KINDS[i.kind].role == "controller" and getattr(i.params, "active", 1)
               for s in (i.options.get("outputs") or {}).values()]
    commands = tuple(sorted(dict.fromkeys(written), key=lambda s: order.get(s.split(".", 1)[0], len(order))))
    substitutes = {f"{i.name}.{a}": f"{i.name}.{b}" for i in inst for a, b in KINDS[i.kind].SUBSTITUTES.items()}
    unmeasured = frozenset(f"{i.name}.{o}" for i in inst for o in KINDS[i.kind].UNMEASURED)
    own = tuple(f"{i.name}.{c}" for i in inst for c in KINDS[i.kind].COMMANDS if f"{i.name}.{c}" not in commands)
    fed = [i for i in inst if i.kind == "storage" and any(j.options.get("storage") == i.name and
                                                         "storage_top" in j.options for j in inst)]
    buffer = None
    if fed:
        b = fed[0]
        n = b.options.get("sensors", 10) if isinstance(b.options.get("sensors"), int) else 10
        buffer = (b.name, float(b.params.volume), tuple(f"{b.name}.T_sensor_{k}" for k in range(1, n + 1)))
    return Roles(str(house), generators, circuits, chargers, commands, substitutes, unmeasured,
                 catalogue_of(house), buffer, _subsystems(inst), loops, own, _source_pipes(runs))


def _source_pipes(runs) -> dict:
    """Pipe sensor on a unit's source loop (SOURCE_PIPES) -> (the loop's flow, the unit's RUN
    command, its threshold): the loop runs when the unit does."""
    out = {}
    for i in runs:
        k = KINDS[i.kind]
        for sensor, flow in k.SOURCE_PIPES.items():
            link, output = flow.split(".", 1)
            out[f"{i.name}.{sensor}"] = (f"{i.options[link]}.{output}", f"{i.name}.{k.RUN[0]}", k.RUN[1])
    return out


def _subsystems(inst) -> dict:
    """Instance -> subsystem, by kind and role: the generators; the coupling point (its headers,
    valves); the storage a coupling point or valve feeds, hot water (a storage only a coil or a
    draw reaches, its coil and draw); the heating circuit (station and emitter); the room; the
    solar loop; the ground source; the substation."""
    fed = {i.options.get("storage") for i in inst if "storage_top" in i.options or i.kind == "branch"}
    out = {}
    for i in inst:
        role = KINDS[i.kind].role
        if i.kind == "substation":
            out[i.name] = "substation"
        elif role == "generator":
            out[i.name] = "generators"
        elif i.kind in ("coupling_point", "header", "branch"):
            out[i.name] = "coupling point"
        elif role == "storage" or role == "heater":
            out[i.name] = "storage" if (i.name if role == "storage" else i.options.get("storage")) in fed else "hot water"
        elif i.kind in ("coil", "dhw_draw", "dhw_coil_draw"):
            out[i.name] = "hot water"
        elif i.kind == "mixing_station" or role == "emitter":
            out[i.name] = "heating circuit"
        elif role == "zone":
            out[i.name] = "room"
        elif i.kind == "solar_collector":
            out[i.name] = "solar"
        elif role == "source":
            out[i.name] = "ground source"
        elif i.kind == "pv":
            out[i.name] = "PV"
    return out
