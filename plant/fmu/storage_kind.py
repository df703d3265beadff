"""The stratified storage as an FMU component kind (`kind = "storage_fmu"`): an FMI co-simulation
FMU takes the place of the native kernel on a coupling point's top and bottom ports.

    [storage]
    kind = "storage_fmu"
    fmu = "storage.fmu"          # path, relative to the house file
    volume = 0.8                 # the plant's view of the tank: SOC, E_stored, stored energy
    n_layers = 40                # = number of T_layer outputs bound below
    [storage.bindings]           # role = "FMU variable" or { var = "...", unit = "K" }
    m_flow = "m_flow"            # inputs: signed flow (> 0 charging: in at the top, out at the bottom)
    T_in_top = "T_in_top"
    T_in_bottom = "T_in_bottom"
    T_out = "T_out"              # outputs: mean outflow temperature over the step
    Q_loss = "Q_loss"            #   heat loss over the step
    T_layer = "T_layer[{i}]"     #   layer temperatures, {i} = 1 (top) ... n_layers
    [storage.parameters]         # FMU parameters: name = value or { value = ..., unit = "degC" }

`unit` names the unit of the FMU variable; it is converted to the plant's unit of the role
(STORAGE_ROLES) and must agree with the unit the FMU declares. Optional roles T_top, T_bottom,
T_sensor_1 ... T_sensor_10 overwrite those storage signals with the FMU's own values.

The compiled step calls the FMU's doStep through numba's object mode (about 3 µs of overhead a
step besides the FMU itself), so the house keeps one step, one clock and one ledger; the FMU's
T_out and Q_loss enter the ledger, its T_layer outputs are the storage state. An FMU's state
cannot be copied: snapshot/restore are not available for such a house.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..component import Kind as ComponentKind, is_number, link
from ..components import storage, storage_kind
from ..errors import did_you_mean
from ..housefile import line_of

_RUNNING: dict[int, "_Runtime"] = {}
_KEYS = itertools.count(1)


def step(key, h, m_flow, T_in_top, T_in_bottom):
    """Called from the compiled step (object mode): one doStep of the FMU registered as `key`."""
    return _RUNNING[key].step(h, m_flow, T_in_top, T_in_bottom)


class _Runtime:
    def __init__(self, comp, y):
        self.comp, self.y = comp, y

    def step(self, h, m_flow, T_in_top, T_in_bottom):
        if h > 0.0:
            self.comp.set_inputs((m_flow, T_in_top, T_in_bottom))
            self.y = self.comp.step(h)
        return self.y


# heating-storage FMU roles -> (causality, plant unit); T_layer is a template over the layers
STORAGE_ROLES = {
    "m_flow": ("input", "kg/s"), "T_in_top": ("input", "degC"), "T_in_bottom": ("input", "degC"),
    "T_out": ("output", "degC"), "Q_loss": ("output", "W"), "T_layer": ("output", "degC"),
    "T_top": ("output", "degC"), "T_bottom": ("output", "degC"),
    **{f"T_sensor_{i}": ("output", "degC") for i in range(1, 11)},
}
STORAGE_REQUIRED = ("m_flow", "T_in_top", "T_in_bottom", "T_out", "Q_loss", "T_layer")


@dataclass(frozen=True)
class StorageFmuSpec:
    """The heating storage as an FMU: file, role -> (FMU variable, FMU unit or None), parameters."""

    path: Path
    bindings: dict  # role -> (variable, unit | None); T_layer's variable holds "{i}"
    parameters: dict  # FMU variable -> (value, unit | None)

    def layer(self, i: int) -> str:
        """The FMU variable of layer i (1 = top): the T_layer binding with {i} filled in."""
        return self.bindings["T_layer"][0].replace("{i}", str(i))


def storage_fmu_spec(name: str, values: dict, path: Path, text: str, problems: list) -> StorageFmuSpec | None:
    """Validate the `fmu`, `bindings` and `parameters` of a storage_fmu instance."""
    from .component import UNITS

    fmu = values.get("fmu")
    bindings = values.get("bindings")
    parameters = values.get("parameters")
    where = f"{path}:{line_of(text, name, 'fmu')} [{name}] fmu"
    if not isinstance(fmu, str) or not fmu:
        problems.append(f"{where} = {fmu!r}: must be the path of a .fmu file (string)")
        return None
    fmu_path = Path(fmu) if Path(fmu).is_absolute() else path.parent / fmu
    if not fmu_path.is_file():
        problems.append(f"{where} = {fmu!r}: no such file ({fmu_path})")
    out = {}
    if not isinstance(bindings, dict):
        problems.append(f"{where}: needs a [{name}.bindings] table; required roles: "
                        + ", ".join(STORAGE_REQUIRED))
        bindings = {}
    for role, b in bindings.items():
        loc = f"{path}:{line_of(text, name + '.bindings', role)} [{name}.bindings] {role}"
        if role not in STORAGE_ROLES:
            problems.append(f"{loc}: unknown role; "
                            + did_you_mean(role, STORAGE_ROLES, f"allowed: {', '.join(STORAGE_ROLES)}", n=2))
            continue
        if isinstance(b, str):
            var, unit = b, None
        elif isinstance(b, dict) and set(b) <= {"var", "unit"} and isinstance(b.get("var"), str):
            var, unit = b["var"], b.get("unit")
        else:
            problems.append(f"{loc} = {b!r}: expected \"FMU variable\" or {{ var = \"...\", unit = \"K\" }}")
            continue
        ours = STORAGE_ROLES[role][1]
        if unit is not None and (unit not in UNITS or UNITS[unit][0] != UNITS[ours][0]):
            dim = UNITS[unit][0] if unit in UNITS else "unknown unit"
            problems.append(f"{loc}: unit mismatch, unit = {unit!r} ({dim}) cannot be converted to the "
                            f"role's {ours!r} ({UNITS[ours][0]})")
            continue
        if role == "T_layer" and "{i}" not in var:
            problems.append(f"{loc} = {var!r}: must contain {{i}} (layer 1 = top ... n_layers), "
                            "e.g. \"T_layer[{i}]\"")
            continue
        out[role] = (var, unit)
    missing = [r for r in STORAGE_REQUIRED if r not in bindings]
    if missing:
        problems.append(f"{path}:{line_of(text, name + '.bindings')} [{name}.bindings]: missing "
                        f"role(s) {', '.join(missing)}")
    params = {}
    for pname, v in (parameters or {}).items():
        loc = f"{path}:{line_of(text, name + '.parameters', pname)} [{name}.parameters] {pname}"
        if isinstance(v, dict) and set(v) <= {"value", "unit"} and "value" in v:
            value, unit = v["value"], v.get("unit")
        else:
            value, unit = v, None
        if not is_number(value):
            problems.append(f"{loc} = {v!r}: expected a number or {{ value = 70.0, unit = \"degC\" }}")
            continue
        if unit is not None and unit not in UNITS:
            problems.append(f"{loc}: unit {unit!r} unknown; known: {', '.join(sorted(u for u in UNITS if u))}")
            continue
        params[pname] = (value, unit)
    return StorageFmuSpec(path=fmu_path, bindings=out, parameters=params)



class Kind(ComponentKind):
    name = "storage_fmu"
    Params = storage.Params
    role = "storage"
    runtime = True
    LINKS = {"fmu": link(None, "path of the storage FMU, relative to the house file", type=Path),
             "bindings": link(None, "role = FMU variable (m_flow, T_in_top, T_in_bottom, T_out, Q_loss, T_layer)",
                              type=dict),
             "parameters": link({}, "FMU parameters: name = value or { value = ..., unit = ... }", type=dict),
             "sensors": storage_kind.Kind.LINKS["sensors"]}

    def initial_state(self, inst):
        return storage.initial_state(inst.params)

    def stored_energy(self, inst, x):
        return storage_kind.Kind().stored_energy(inst, x)

    def emit(self, c, inst):
        a = inst.name
        spec = storage_fmu_spec(a, inst.options, c.decl.path, c.decl.path.read_text(), c.problems)
        c.values[f"{a}.layers"], _, c.values[f"{a}.Q_loss"] = storage_kind.Kind().emit_signals(c, inst)
        # the key of the running FMU (House.reset), and the FMU outputs that overwrite signals
        c.values[f"{a}.fmu_key"] = c.param(inst, np.zeros(1), suffix="_fmu") + "[0]"
        c.values[f"{a}.fmu_signals"] = self._extra(a, spec)

    def allocate(self, c, inst, ports):
        """The FMU call, once the coupling point has said what flows in (its values)."""
        a, N = inst.name, inst.params.n_layers
        flows = c.values.get(f"{a}.fmu_inputs")
        if flows is None or ports.n_in != 1 or ports.n_out != 1 or ports.n_coil:
            c.problems.append(f"{inst.where}: a storage FMU sits on one coupling point's top and bottom "
                              "ports only (no coils, draws or inlet mixing)")
            flows = ("0.0", "0.0", "0.0")
        storage_kind.Kind().allocate(c, inst, ports)
        y, Ql = c.var("y_fmu"), c.values[f"{a}.Q_loss"]
        mod = c.module(__name__)
        c.emit("storages",
               "with objmode(" + y + "='float64[:]'):",
               f"    {y} = {mod}.step(int({c.values[f'{a}.fmu_key']}), h, {flows[0]}, {flows[1]}, {flows[2]})",
               f"{c.values[f'{a}.layers']}[:] = {y}[:{N}]",
               f"{ports.array('out_T')}[0] = {y}[{N}]",
               f"{Ql} = {y}[{N + 1}]")
        for i_out, signal in enumerate(c.values[f"{a}.fmu_signals"]):
            c.emit("signals", f"{c.s(signal)} = {y}[{N + 2 + i_out}]")

    @staticmethod
    def _extra(name, spec):
        b = spec.bindings if spec else {}
        roles = [("T_top", "T_top"), ("T_bottom", "T_bot"),
                 *((f"T_sensor_{i}", f"T_sensor_{i}") for i in range(1, 11))]
        return [f"{name}.{sig}" for role, sig in roles if role in b]

    def start(self, inst, x, p):
        """Instantiate the FMU at time 0, register it, take its layer temperatures as the state."""
        from .component import FmuComponent

        spec = _spec_at_start(inst)
        b, N = spec.bindings, inst.params.n_layers
        inputs = {r: (b[r][0], STORAGE_ROLES[r][1], b[r][1]) for r in ("m_flow", "T_in_top", "T_in_bottom")}
        outputs = {f"T_layer_{i}": (spec.layer(i), "degC", b["T_layer"][1]) for i in range(1, N + 1)}
        outputs["T_out"] = (b["T_out"][0], "degC", b["T_out"][1])
        outputs["Q_loss"] = (b["Q_loss"][0], "W", b["Q_loss"][1])
        for role in ("T_top", "T_bottom", *(f"T_sensor_{i}" for i in range(1, 11))):
            if role in b:
                outputs[role] = (b[role][0], "degC", b[role][1])
        comp = FmuComponent(spec.path, inputs=inputs, outputs=outputs,
                            parameters=spec.parameters, start_time=0.0)
        y = comp.read_outputs()
        x[:] = y[:N]
        key = next(_KEYS)
        _RUNNING[key] = _Runtime(comp, y)
        p[0] = key
        return key

    def stop(self, key):
        run = _RUNNING.pop(key, None)
        if run is not None:
            run.comp.close()


def _spec_at_start(inst) -> StorageFmuSpec:
    """The spec the compiler checked, built again from the instance's links when the house starts
    the FMU (the compiler reported its problems; the house file is the one its `where` names)."""
    return storage_fmu_spec(inst.name, inst.options, Path(inst.where.partition(":")[0]), "", [])
