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

from dataclasses import dataclass, field

import numpy as np

from .component import Instance, SignalName, is_number, pack
from .errors import ConfigError, did_you_mean
from .generated import PHASES, load_module, source  # noqa: F401 (load_module: House)
from .signals import Signal, SignalCatalogue

EMIT_ORDER = {"boundary": 0, "storage": 1, "connection": 2, "zone": 4, "controller": 5, "sensor": 6}
LEDGER_CATEGORIES = ("fuel", "el", "heat", "building", "dhw", "loss", "missing")


@dataclass
class StoragePorts:
    """Port slots of one storage, requested by the connections attached to it, and the names of
    its port arrays in the step (`array`, `coil_heat`): no kind spells them."""

    storage: str                                     # the storage's instance name
    n_in: int = 0
    n_out: int = 0
    n_coil: int = 0
    fixed_in: list = field(default_factory=list)     # (slot, layer) set at compile time
    fixed_out: list = field(default_factory=list)
    coils: list = field(default_factory=list)        # (slot, top layer, bottom layer)
    ARRAYS = ("in_layer", "in_m", "in_T", "out_layer", "out_m", "out_T",  # per inflow, outflow slot; per coil;
              "coil_top", "coil_bot", "coil_UA", "coil_m", "coil_Tin", "coil_Tout",
              "q", "fin_layer", "fin_m", "fout_layer", "fout_m")  # scratch: the kernel's (step_into's) order

    def array(self, what: str) -> str:
        """The name in the step of the port array `what` (one of ARRAYS)."""
        if what not in self.ARRAYS:
            raise KeyError(f"{what!r}: no port array of a storage; one of {', '.join(self.ARRAYS)}")
        return f"{self.storage}_{what}"

    def coil_heat(self, k: int) -> str:
        """The local of coil k's heat into the storage this step (set by the storage's allocate)."""
        return f"{self.storage}_coil_Q_{k}"

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
        # ia[0] and ia[1]: the bounds of every state and parameter slot, read at run time, so
        # plants that differ only in the sizes of their arrays (a storage's layer count) share one
        # generated source, hence one compiled plant per machine
        self.ia: list[np.ndarray] = [np.zeros(0, dtype=np.int64), np.zeros(0, dtype=np.int64)]
        self.fa: list[np.ndarray] = []
        self.ledger: list[tuple[str, str, str]] = []  # (key, instance, category)
        self.ports: dict[str, StoragePorts] = {}
        self.heat_to: dict[str, list[str]] = {}       # zone -> heat-flow locals of its emitters
        self.values: dict[str, str] = {}              # "instance.quantity" -> local of this step
        self.energy: list = []                        # (instance, fn(x, params) -> J)
        self.failed: set[str] = set()              # instances whose links were reported bad
        self.reads: dict[str, Instance] = {}       # instance -> the first that reads its state (state_of)
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
        return self._slot("x", self.x0, self.x_slices, inst.name + suffix, x0)

    def param(self, inst: Instance, values: np.ndarray, suffix: str = "") -> str:
        return self._slot("p", self.p0, self.p_slices, inst.name + suffix, values)

    def views(self, inst: Instance, x0: np.ndarray | None = None) -> tuple[str, str]:
        """(state view, parameter view) of an instance several kinds reach (a header, zone, emitter,
        collector); the first call allocates them: x0 (else its initial_state), its packed Params."""
        if inst.name not in self.x_slices:
            self.state(inst, self.kinds[inst.kind].initial_state(inst) if x0 is None else x0)
            self.param(inst, pack(inst.params))
        return f"x_{inst.name}", f"p_{inst.name}"

    def state_of(self, inst: Instance, other: Instance) -> str:
        """The view of another instance's state, for inst's code to read or update. Never
        allocated here (other's own kind does, wherever it emits, so the layout does not depend on
        who asks first); a state nobody allocates is a problem at assembly."""
        self.reads.setdefault(other.name, inst)
        return f"x_{other.name}"

    def _slot(self, array: str, chunks: list, slices: dict, key: str, values) -> str:
        a = sum(len(v) for v in chunks)
        values = np.ascontiguousarray(values, dtype=np.float64)
        chunks.append(values)
        k, i = 2 * len(slices), 0 if array == "x" else 1  # ia[i] = the slices' bounds in order (compile_plant)
        slices[key] = (a, a + len(values))
        view = f"{array}_{key}"
        self.header.append(f"{view} = {array}[ia[{i}][{k}]:ia[{i}][{k + 1}]]")
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
        if self.has_signal(name):
            self.problems.append(f"signal {name!r} declared twice (two components claim it)")
        self._sig_index[name] = len(self._signals)
        self._signals.append((order, len(self._signals), name, unit, causality, description))
        return self.s(name)

    def has_signal(self, name: str) -> bool:
        """Whether a kind has declared the signal `name` so far (in emission order)."""
        return name in self._sig_index

    def signal_index(self, name: str) -> str:
        """The index of a signal in s, as the step's source writes it (resolved at assembly)."""
        return f"§{name}§"

    def s(self, name: str) -> str:
        """The slot of a signal that some kind declares (resolved after every kind has emitted)."""
        return f"s[{self.signal_index(name)}]"

    def remote(self, name: str) -> str:
        return f"remote[{self.signal_index(name)}]"

    def write_command(self, phase: str, target: str, expr: str) -> None:
        """A controller writes an input unless it is driven from outside (remote, bound)."""
        self.emit(phase, f"if not {self.remote(target)}:", f"    {self.s(target)} = {expr}")

    def ledger_entry(self, inst: Instance, category: str) -> str:
        key = f"{category}_{inst.name}"
        self.ledger.append((key, inst.name, category))
        return f"ledger[{len(self.ledger) - 1}]"

    def storage_ports(self, storage: str, ask: bool = True) -> StoragePorts:
        """The ports of `storage` and the names of its arrays. A connection asks for them (the
        storage allocates them at assembly, in the order first asked for); the storage's own code
        passes ask=False: it emits before the connections that ask."""
        return self.ports.setdefault(storage, StoragePorts(storage)) if ask else \
            self.ports.get(storage) or StoragePorts(storage)

    def port_layer(self, inst: Instance, key: str, storage: str) -> int:
        """Layer of the port inst.options[key] (a height in m) in `storage`; a height outside the
        tank is a problem naming the instance, key and the allowed range."""
        return self._layer(inst.at(key), inst.options[key], storage)

    def _layer(self, where: str, h, storage: str) -> int:
        st = self.instances[storage]
        H, n = st.params.height, st.params.n_layers
        if not is_number(h) or not 0.0 <= h <= H:
            self.problems.append(f"{where} = {h!r}: outside the storage {storage!r}; "
                                 f"allowed 0 … {H} m (its height)")
            return 0
        return n - 1 - min(int(h / H * n), n - 1)

    def port_layers(self, inst: Instance, key: str, storage: str) -> tuple[int, int]:
        """(upper, lower) layers of a port that is a height (the same layer twice) or a three-way
        valve's { upper = ..., lower = ... } (the lab's SwitchPort, reference §8.4); each side's
        problems name `key.upper` / `key.lower` at the key's line."""
        v = inst.options[key]
        if not isinstance(v, dict):
            layer = self.port_layer(inst, key, storage)
            return layer, layer
        if set(v) != {"upper", "lower"}:
            self.problems.append(f"{inst.at(key)} = {v!r}: a three-way valve needs {{ upper = ..., lower = ... }}")
            return 0, 0
        return tuple(self._layer(f"{inst.at(key)}.{side}", v[side], storage) for side in ("upper", "lower"))

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
                self.problems.append(f"signal {part!r} is read but no component provides it; "
                                     + did_you_mean(part, catalogue.names,
                                                    "check the links of the controllers and connections"))
                out.append("0")
        return "".join(out)


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
    for inst in c.instances.values():
        for key, spec in c.kinds[inst.kind].LINKS.items():
            name = inst.options.get(key)
            if spec.type is SignalName and isinstance(name, str) and name not in catalogue:
                c.problems.append(f"{inst.at(key)} = {name!r}: no such signal; "
                                  + did_you_mean(name, catalogue.names, "list them with `twin signals`"))
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
                    c.problems.append(f"{inst.at(table)}.{key} = {name!r}: no such signal; "
                                      + did_you_mean(name, catalogue.names, "list them with `twin signals`"))
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
        except (KeyError, TypeError, AttributeError, ValueError):
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
            except (KeyError, TypeError, AttributeError, ValueError):
                if not decl.problems:
                    raise
        elif not problems:
            raise ConfigError(f"{name!r}: ports asked of an instance that is no storage")
    for name, user in c.reads.items():
        if name not in c.x_slices and not problems:
            problems.append(f"{user.where}: reads the state of {name!r}, but no kind allocates one")
    catalogue = c.catalogue()
    _check_controller_links(c, catalogue)
    text = source(c, catalogue)
    if problems:
        raise ConfigError("\n".join(dict.fromkeys(problems)))
    x0 = np.concatenate(c.x0) if c.x0 else np.zeros(0)
    p = np.concatenate(c.p0) if c.p0 else np.zeros(0)
    tabs = tuple(c.tabs) if c.tabs else (np.zeros((1, 1)),)
    c.ia[0], c.ia[1] = (np.array([b for ab in sl.values() for b in ab], dtype=np.int64)
                        for sl in (c.x_slices, c.p_slices))
    ia = tuple(c.ia)
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
