"""The compiler: a house declaration -> signal catalogue, state/parameter layout and one compiled step.

Every component kind (plant/components/, plant/controllers/, plant/connections/) emits the lines
of its part of the step into named phases through a `Context`; the context hands out the slots
(state, parameters, tables, port arrays, signals, ledger entries), so no kind knows another's
layout and nothing outside this module indexes an array by a hand-written number. The assembled
source is written to a cache file named after its hash and imported, so numba compiles each
distinct plant once per machine (cache=True needs a real file).

Step phases, in order. All coupling uses start-of-step states, so every enthalpy flow is counted
once at its source and once at its sink and the energy ledger closes to round-off:
  boundary    profiles and weather at the step's local time
  sense       sensor signals from the start-of-step states
  setpoints   schedules (room set-points)
  control     built-in controllers write the commands not driven from outside
  hydraulics  coupling points: consumer requests, generators, storage port requests
  draws       tap draws from storages
  storages    storages serve their port requests
  rooms       zones take the heat of their emitters
  volumes     mixed volumes (headers) take what flows in
  signals     end-of-step signals and the ledger
"""
from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from .errors import ConfigError
from .signals import Signal, SignalCatalogue

PHASES = ("boundary", "sense", "setpoints", "control", "hydraulics", "draws", "storages", "rooms",
          "volumes", "signals")
EMIT_ORDER = {"boundary": 0, "storage": 1, "connection": 2, "zone": 4, "controller": 5}
LEDGER_CATEGORIES = ("fuel", "el", "heat", "building", "dhw", "loss", "missing")


@dataclass
class Instance:
    """One declared component or connection: its name, kind, parameters and link options."""

    name: str
    kind: str
    params: object            # the kind's frozen Params instance (or None)
    options: dict             # link keys (instance names, heights, shares ...), validated by the kind
    where: str                # "file:line [name]" for messages
    order: int = 0            # declaration order (catalogue grouping)
    lines: dict = field(default_factory=dict)  # key -> line in the house file

    def at(self, key: str) -> str:
        """"file:line [name] key" of one key (its own line when known)."""
        path, _, rest = self.where.partition(":")
        line = self.lines.get(key)
        return f"{path}:{line} {rest.split(' ', 1)[1]} {key}" if line else f"{self.where} {key}"


@dataclass
class StoragePorts:
    """Port slots of one storage, requested by the connections attached to it."""

    n_in: int = 0
    n_out: int = 0
    n_coil: int = 0
    fixed_in: list = field(default_factory=list)     # (slot, layer) set at compile time
    fixed_out: list = field(default_factory=list)
    coils: list = field(default_factory=list)        # (slot, top layer, bottom layer)
    users: dict = field(default_factory=dict)        # (user, key) -> slot: a port connected twice

    def _claim(self, inst, key, problems):
        if (inst.name, key) in self.users:
            problems.append(f"{inst.where} {key}: port connected twice")
        self.users[(inst.name, key)] = True

    def add_inlet(self, inst, key, layer, n=1):
        """n inflow slots (layer None: set at run time by the user); returns the first slot."""
        slot = self.n_in
        self.n_in += n
        if layer is not None:
            self.fixed_in.extend((slot + i, layer) for i in range(n))
        return slot

    def add_outlet(self, inst, key, layer):
        slot = self.n_out
        self.n_out += 1
        if layer is not None:
            self.fixed_out.append((slot, layer))
        return slot

    def add_coil(self, inst, top, bottom):
        slot = self.n_coil
        self.n_coil += 1
        self.coils.append((slot, top, bottom))
        return slot


class Context:
    """What the kinds emit into: code per phase, and every slot of the plant's arrays."""

    def __init__(self, instances: dict[str, Instance], kinds: dict, problems: list[str]):
        self.instances = instances
        self.kinds = kinds
        self.problems = problems
        self.lines = {ph: [] for ph in PHASES}
        self.header: list[str] = []
        self.imports: dict[str, str] = {}         # alias -> module path
        self._signals: list[tuple] = []            # (order, seq, name, unit, causality, description)
        self._sig_index: dict[str, int] = {}
        self.x0: list[np.ndarray] = []
        self.x_slices: dict[str, tuple[int, int]] = {}
        self.p0: list[np.ndarray] = []
        self.p_slices: dict[str, tuple[int, int]] = {}
        self.tabs: list[np.ndarray] = []
        self.ia: list[np.ndarray] = []
        self.fa: list[np.ndarray] = []
        self.ledger: list[tuple[str, str, str]] = []  # (key, instance, category)
        self.ports: dict[str, StoragePorts] = {}
        self.heat_to: dict[str, list[str]] = {}       # zone -> heat-flow locals of its emitters
        self.values: dict[str, str] = {}              # "instance.quantity" -> local of this step
        self.energy: list = []                        # (instance, fn(x, params) -> J)
        self.failed: set[str] = set()              # instances whose links were reported bad
        self.n_x = 0
        self.n_p = 0
        self._n_var = 0

    # --- code ----------------------------------------------------------------------------
    def module(self, path: str) -> str:
        """An alias under which the generated source imports a kernel module."""
        alias = "_" + path.rsplit(".", 1)[-1]
        while alias in self.imports and self.imports[alias] != path:
            alias += "_"
        self.imports[alias] = path
        return alias

    def var(self, hint: str) -> str:
        self._n_var += 1
        return f"{hint}_{self._n_var}"

    def emit(self, phase: str, *lines: str) -> None:
        self.lines[phase].extend(lines)

    # --- slots ---------------------------------------------------------------------------
    def state(self, inst: Instance, x0: np.ndarray, suffix: str = "") -> str:
        """Allocate the instance's state vector (a second one with a suffix); returns the name of
        its view in the step."""
        a = self.n_x
        x0 = np.ascontiguousarray(x0, dtype=np.float64)
        self.n_x += len(x0)
        self.x0.append(x0)
        self.x_slices[inst.name + suffix] = (a, self.n_x)
        view = f"x_{inst.name}{suffix}"
        self.header.append(f"{view} = x[{a}:{self.n_x}]")
        return view

    def param(self, inst: Instance, values: np.ndarray, suffix: str = "") -> str:
        a = self.n_p
        values = np.ascontiguousarray(values, dtype=np.float64)
        self.n_p += len(values)
        self.p0.append(values)
        self.p_slices[inst.name + suffix] = (a, self.n_p)
        view = f"p_{inst.name}{suffix}"
        self.header.append(f"{view} = p[{a}:{self.n_p}]")
        return view

    def table(self, array: np.ndarray) -> str:
        for i, t in enumerate(self.tabs):
            if t is array:
                return f"tabs[{i}]"
        self.tabs.append(np.ascontiguousarray(array, dtype=np.float64))
        return f"tabs[{len(self.tabs) - 1}]"

    def int_array(self, values) -> str:
        self.ia.append(np.array(values, dtype=np.int64).reshape(-1))
        return f"ia[{len(self.ia) - 1}]"

    def float_array(self, n: int) -> str:
        self.fa.append(np.zeros(n, dtype=np.float64))
        return f"fa[{len(self.fa) - 1}]"

    def signal(self, inst: Instance, local: str, unit: str, causality: str, description: str,
               order: int | None = None) -> str:
        """Declare the signal inst.local; returns its slot expression s[i] (resolved at assembly)."""
        name = f"{inst.name}.{local}"
        return self.named_signal(name, unit, causality, description, inst.order if order is None else order)

    def named_signal(self, name: str, unit: str, causality: str, description: str, order: int) -> str:
        if name in self._sig_index:
            self.problems.append(f"signal {name!r} declared twice (two components claim it)")
        self._sig_index[name] = len(self._signals)
        self._signals.append((order, len(self._signals), name, unit, causality, description))
        return f"s[§{name}§]"

    def s(self, name: str) -> str:
        """The slot of a signal that some kind declares (resolved after every kind has emitted)."""
        return f"s[§{name}§]"

    def remote(self, name: str) -> str:
        return f"remote[§{name}§]"

    def write_command(self, phase: str, target: str, expr: str) -> None:
        """A controller writes an input unless it is driven from outside (remote, bound)."""
        self.emit(phase, f"if not {self.remote(target)}:", f"    {self.s(target)} = {expr}")

    def ledger_entry(self, inst: Instance, category: str) -> str:
        key = f"{category}_{inst.name}"
        self.ledger.append((key, inst.name, category))
        return f"ledger[{len(self.ledger) - 1}]"

    def storage_ports(self, storage: str) -> StoragePorts:
        return self.ports.setdefault(storage, StoragePorts())

    def port_layer(self, inst: Instance, key: str, storage: str) -> int:
        """Layer of the port inst.options[key] (a height in m) in `storage`; a height outside the
        tank is a problem naming the instance, key and the allowed range."""
        st = self.instances[storage]
        h = inst.options[key]
        H, n = st.params.height, st.params.n_layers
        if not isinstance(h, (int, float)) or isinstance(h, bool) or not 0.0 <= h <= H:
            self.problems.append(f"{inst.at(key)} = {h!r}: outside the storage {storage!r}; "
                                 f"allowed 0 … {H} m (its height)")
            return 0
        return n - 1 - min(int(h / H * n), n - 1)

    # --- assembly ------------------------------------------------------------------------
    def catalogue(self) -> SignalCatalogue:
        """Inputs first, then every instance's signals in declaration order."""
        rows = sorted(self._signals, key=lambda r: (r[4] != "input", r[0], r[1]))
        return SignalCatalogue([Signal(r[2], r[3], r[4], r[5]) for r in rows])

    def resolve(self, code: str, catalogue: SignalCatalogue) -> str:
        out = []
        parts = code.split("§")
        for i, part in enumerate(parts):
            if i % 2 == 0:
                out.append(part)
            elif part in catalogue:
                out.append(str(catalogue.index(part)))
            elif self.problems:
                out.append("0")  # a consequence of a problem reported already
            else:
                from difflib import get_close_matches

                close = get_close_matches(part, catalogue.names, n=3, cutoff=0.6)
                self.problems.append(f"signal {part!r} is read but no component provides it; "
                                     + (f"did you mean {', '.join(close)}?" if close else
                                        "check the links of the controllers and connections"))
                out.append("0")
        return "".join(out)


def _indent(lines, n):
    return [" " * n + line for line in lines]


def source(c: Context, catalogue: SignalCatalogue) -> str:
    """The generated module: step, run and drive over the plant's flat arrays."""
    body = _indent(c.header, 4)
    for ph in PHASES:
        if c.lines[ph]:
            body.append(f"    # {ph}")
            body.extend(_indent(c.lines[ph], 4))
    imports = "\n".join(f"import {path} as {alias}" for alias, path in sorted(c.imports.items()))
    text = f'''"""Generated by plant/compiler.py from a house declaration; do not edit."""
import math
import numpy as np
from numba import njit, objmode  # noqa: F401 (FMU kinds call out of the step)
from plant.schedule import apply_bindings, drive_plan, n_steps
from plant.water import CP, RHO
{imports}


@njit(cache=True)
def step(t, h, x, p, s, remote, ledger, tabs, prof, ia, fa, bind):
    apply_bindings(t, h, bind, s)
{chr(10).join(body)}


@njit(cache=True)
def run(n, h, t0, x, p, s, remote, ledger, tabs, prof, ia, fa, bind, out, rec_every):
    rows = 0
    for k in range(n):
        t = t0 + k * h
        step(t, h, x, p, s, remote, ledger, tabs, prof, ia, fa, bind)
        if rec_every > 0 and (k + 1) % rec_every == 0 and rows < out.shape[0]:
            out[rows, 0] = t + h
            out[rows, 1:] = s
            rows += 1
    return rows


@njit(cache=True)
def drive(times, cmd, x, p, s, remote, ledger, tabs, prof, ia, fa, bind, out):
    """Run to times[-1] through the spans of drive_plan (the bound commands switch at the
    spans' midpoints); out[i] = the signals at times[i]."""
    no_out = np.zeros((0, s.shape[0] + 1))
    for seg in drive_plan(times, cmd):
        a, b, rec = seg[0], seg[1], int(seg[3])
        if b > a:
            n = n_steps(b - a)
            run(n, (b - a) / n, a, x, p, s, remote, ledger, tabs, prof, ia, fa, bind, no_out, 0)
        else:
            apply_bindings(a, 0.0, bind, s)
        if rec >= 0:
            out[rec] = s
'''
    return c.resolve(text, catalogue)


def cache_dir() -> Path:
    """Where generated plants live (beside numba's cache: plant/__init__.py)."""
    import numba

    return Path(numba.config.CACHE_DIR) / "plants"


def load_module(text: str):
    """Import the generated source from a file named after its hash (written once)."""
    digest = hashlib.sha256(text.encode()).hexdigest()[:20]
    name = f"twin_plant_{digest}"
    if name in sys.modules:
        return sys.modules[name]
    folder = cache_dir()
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / f"{name}.py"
    if not path.exists() or path.read_text() != text:
        tmp = path.with_suffix(f".{os.getpid()}.tmp")
        tmp.write_text(text)
        os.replace(tmp, path)
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module
    spec.loader.exec_module(module)
    return module


@dataclass
class CompiledPlant:
    """Everything a House needs: catalogue, initial arrays, the compiled module, the ledger."""

    catalogue: SignalCatalogue
    x0: np.ndarray
    p: np.ndarray
    tabs: tuple
    prof: tuple
    ia: tuple
    fa: tuple
    ledger: list            # (key, instance, category)
    energy: list            # (instance, fn(x_slice) -> J)
    x_slices: dict
    p_slices: dict
    source: str
    module: object = None


def _owners_of_failed(c: Context) -> set[str]:
    """Instances whose signals a failed instance would have declared (its generators, consumers,
    emitter)."""
    out = set()
    for name in c.failed:
        for v in c.instances[name].options.values():
            for n in (v if isinstance(v, list) else [v]):
                if isinstance(n, str) and n in c.instances and \
                        c.kinds[c.instances[n].kind].role in ("generator", "consumer", "emitter"):
                    out.add(n)
    return out


def _check_controller_links(c: Context, catalogue: SignalCatalogue) -> None:
    """Every controller reads signals that exist and writes inputs (with the closest names)."""
    from difflib import get_close_matches

    for inst in c.instances.values():
        for table, want in (("inputs", None), ("outputs", "input")):
            links = inst.options.get(table) if isinstance(inst.options, dict) else None
            if not isinstance(links, dict) or inst.kind == "profiles":
                continue
            for key, name in links.items():
                name = name.get("signal") if isinstance(name, dict) else name
                if not isinstance(name, str):
                    continue
                owner = name.split(".")[0]
                if name not in catalogue and c.problems and (
                        owner not in c.instances or owner in c.failed | _owners_of_failed(c)):
                    continue  # its owner's bad declaration is reported already
                if name not in catalogue:
                    close = get_close_matches(name, catalogue.names, n=3, cutoff=0.6)
                    c.problems.append(f"{inst.at(table)}.{key} = {name!r}: no such signal; "
                                      + (f"did you mean {', '.join(close)}?" if close else
                                         "list them with `twin signals`"))
                elif want and catalogue.signal(name).causality != want:
                    c.problems.append(f"{inst.at(table)}.{key} = {name!r}: is an "
                                      f"{catalogue.signal(name).causality}; a controller writes inputs: "
                                      + ", ".join(s.name for s in catalogue.inputs()))


def compile_plant(decl) -> CompiledPlant:
    """Declaration (plant/declaration.py) -> CompiledPlant; every problem reported at once."""
    from .kinds import KINDS

    problems: list[str] = list(decl.problems)
    c = Context(decl.instances, KINDS, problems)
    c.decl = decl
    # zones after the connections that fill their heat inputs, controllers last: they read
    # values other kinds compute earlier in the step (set-points, weather)
    for inst in sorted(decl.instances.values(), key=lambda i: EMIT_ORDER.get(KINDS[i.kind].role, 3)):
        try:
            KINDS[inst.kind].emit(c, inst)
        except (KeyError, TypeError, AttributeError):
            if not decl.problems:
                raise  # a kind's own bug, not a consequence of a reported bad link
            c.failed.add(inst.name)
    for inst in decl.instances.values():
        if KINDS[inst.kind].role == "storage":
            c.storage_ports(inst.name)  # a storage nothing is connected to still steps (losses)
    for name, ports in c.ports.items():
        if name in decl.instances and KINDS[decl.instances[name].kind].role == "storage":
            try:
                KINDS[decl.instances[name].kind].allocate(c, decl.instances[name], ports)
            except (KeyError, TypeError, AttributeError):
                if not decl.problems:
                    raise
        elif not problems:
            raise ConfigError(f"{name!r}: ports asked of an instance that is no storage")
    catalogue = c.catalogue()
    _check_controller_links(c, catalogue)
    text = source(c, catalogue)
    if problems:
        raise ConfigError("\n".join(dict.fromkeys(problems)))
    x0 = np.concatenate(c.x0) if c.x0 else np.zeros(0)
    p = np.concatenate(c.p0) if c.p0 else np.zeros(0)
    tabs = tuple(c.tabs) if c.tabs else (np.zeros((1, 1)),)
    ia = tuple(c.ia) if c.ia else (np.zeros(0, dtype=np.int64),)
    fa = tuple(c.fa) if c.fa else (np.zeros(0),)
    return CompiledPlant(catalogue=catalogue, x0=x0, p=p, tabs=tabs, prof=decl.prof, ia=ia, fa=fa,
                         ledger=c.ledger, energy=c.energy, x_slices=c.x_slices,
                         p_slices=c.p_slices, source=text)


def catalogue_of(name_or_path, overrides: dict | None = None) -> SignalCatalogue:
    """The catalogue a house declaration compiles to (no profiles loaded, nothing compiled)."""
    from .declaration import load

    decl = load(name_or_path, overrides)
    decl.instances = {"weather": Instance("weather", "profiles", None, {"tau0": 0.0},
                                          f"{decl.path} [profiles]", -1), **decl.instances}
    return compile_plant(decl).catalogue
