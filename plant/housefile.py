"""House files: load `plant/houses/<name>.toml` (or a path), validate everything, report all problems.

Messages name the file, the line, the key and what is allowed, e.g.
    plant/houses/house1.toml:42 [storage] n_layers = 0: out of range; allowed 3 … 200 1

The whole plant can be an FMU: [house] topology = "fmu", fmu = "plant.fmu", a [bindings] table
from catalogue signals to FMU variables and optional [parameters]; load() then returns an
FmuHouseSpec (syntax: _fmu_house below; the house: plant/fmu/house.py).

The heating storage can be an FMI co-simulation FMU instead of the native kernel:

    [storage]
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
    n_layers = 40

`unit` names the unit of the FMU variable; it is converted to the plant's unit of the role
(STORAGE_ROLES) and must agree with the unit the FMU declares (if it declares one).
Optional roles T_top, T_bottom, T_sensor_1 ... T_sensor_10 overwrite those storage signals with
the FMU's own values after every step.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, fields
from difflib import get_close_matches
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from .component import build_params
from .components import boiler, chp, mixing_station, pipe, radiator, storage, zone, dhw
from .controllers import room_thermostat, rule_based
from .errors import ConfigError

HOUSES = Path(__file__).parent / "houses"

# section -> Params class, for the two-generator topology
COMPONENTS = {
    "chp": chp.Params,
    "boiler": boiler.Params,
    "storage": storage.Params,
    "dhw_storage": storage.Params,
    "zone": zone.Params,
    "radiator": radiator.Params,
    "mixer": mixing_station.Params,
    "thermostat": room_thermostat.Params,
    "dhw": dhw.Params,
    "controller": rule_based.Params,
    "supply_header": pipe.Params,
    "return_header": pipe.Params,
}
TOPOLOGIES = ("two_generator_switch",)  # plus "fmu": the whole plant is an FMU (FmuHouseSpec)


@dataclass(frozen=True)
class Connections:
    """Port heights and loop parameters of the two-generator topology (SI, heights in m)."""

    storage_top_port: float = 1.60
    storage_bottom_port: float = 0.03
    dhw_draw_port: float = 1.48
    dhw_cold_port: float = 0.03
    dhw_coil_top: float = 1.21
    dhw_coil_bottom: float = 0.75
    dhw_coil_UA: float = 640.0
    dhw_pump_flow: float = 0.333
    storage_soc_T0: float = 40.0
    storage_soc_Tmax: float = 80.0
    dhw_soc_T0: float = 15.0
    dhw_soc_Tmax: float = 80.0
    idle_flow_chp: float = 0.0      # share of the consumers' flow deficit (vs the boiler) through the CHP
    pump_coupling_chp: float = 0.0  # share of the boiler flow forced through the CHP
    storage_inlet_mixing: float = 0.0  # m3 beyond the port layer over which a storage inflow spreads


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


def _storage_fmu(values: dict, path: Path, text: str, problems: list) -> StorageFmuSpec | None:
    """Pop `fmu`, `bindings`, `parameters` from the [storage] table and validate them."""
    from .fmu.component import UNITS

    fmu = values.pop("fmu", None)
    bindings = values.pop("bindings", None)
    parameters = values.pop("parameters", None)
    if fmu is None:
        for key, v in (("bindings", bindings), ("parameters", parameters)):
            if v is not None:
                problems.append(f"{path}:{_line(text, 'storage.' + key)} [storage.{key}]: only with "
                                f"[storage] fmu = \"file.fmu\" (the storage is native otherwise)")
        return None
    where = f"{path}:{_line(text, 'storage', 'fmu')} [storage] fmu"
    if not isinstance(fmu, str) or not fmu:
        problems.append(f"{where} = {fmu!r}: must be the path of a .fmu file (string)")
        return None
    fmu_path = Path(fmu) if Path(fmu).is_absolute() else path.parent / fmu
    if not fmu_path.is_file():
        problems.append(f"{where} = {fmu!r}: no such file ({fmu_path})")
    out = {}
    if not isinstance(bindings, dict):
        problems.append(f"{where}: needs a [storage.bindings] table; required roles: "
                        + ", ".join(STORAGE_REQUIRED))
        bindings = {}
    for role, b in bindings.items():
        loc = f"{path}:{_line(text, 'storage.bindings', role)} [storage.bindings] {role}"
        if role not in STORAGE_ROLES:
            close = get_close_matches(role, STORAGE_ROLES, n=2)
            problems.append(f"{loc}: unknown role; " + (f"did you mean {', '.join(close)}?" if close
                                                       else f"allowed: {', '.join(STORAGE_ROLES)}"))
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
        problems.append(f"{path}:{_line(text, 'storage.bindings')} [storage.bindings]: missing "
                        f"role(s) {', '.join(missing)}")
    params = {}
    for name, v in (parameters or {}).items():
        loc = f"{path}:{_line(text, 'storage.parameters', name)} [storage.parameters] {name}"
        if isinstance(v, dict) and set(v) <= {"value", "unit"} and "value" in v:
            value, unit = v["value"], v.get("unit")
        else:
            value, unit = v, None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            problems.append(f"{loc} = {v!r}: expected a number or {{ value = 70.0, unit = \"degC\" }}")
            continue
        if unit is not None and unit not in UNITS:
            problems.append(f"{loc}: unit {unit!r} unknown; known: {', '.join(sorted(u for u in UNITS if u))}")
            continue
        params[name] = (value, unit)
    return StorageFmuSpec(path=fmu_path, bindings=out, parameters=params)


@dataclass(frozen=True)
class HouseSpec:
    name: str
    path: Path
    description: str
    start: str
    household_kwh_per_year: float
    dhw_litres_per_day: float
    typeday: int  # 0: the 2021 year series; 1..11: a type-day block (profiles/loaders.py)
    params: dict  # section -> Params instance
    connections: Connections
    storage_fmu: StorageFmuSpec | None = None  # the heating storage runs as this FMU


def resolve(name_or_path: str | Path) -> Path:
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        if not p.exists():
            raise ConfigError(f"{p}: no such house file")
        return p
    candidate = HOUSES / f"{name_or_path}.toml"
    if not candidate.exists():
        known = sorted(f.stem for f in HOUSES.glob("*.toml"))
        raise ConfigError(f"house {name_or_path!r}: not found; shipped houses: {', '.join(known)}")
    return candidate


def _line(text: str, section: str, key: str | None = None) -> int:
    """Line number of [section] (or of key inside it) in the TOML text; 0 when not found."""
    lines = text.splitlines()
    start = None
    for i, line in enumerate(lines, 1):
        if re.match(rf"^\s*\[{re.escape(section)}\]\s*(#.*)?$", line):
            start = i
            if key is None:
                return i
            continue
        if start is not None:
            if re.match(r"^\s*\[", line):
                break
            if re.match(rf"^\s*([\"']?){re.escape(key)}\1\s*=", line):  # bare or quoted key
                return i
    return start or 0


def load(name_or_path: str | Path, overrides: dict | None = None) -> "HouseSpec | FmuHouseSpec":
    """Load and validate a house file; `overrides` {"section.key": value} replace file values
    (validated like the file; used by fits and parameter studies)."""
    path = resolve(name_or_path)
    text = path.read_text()
    try:
        doc = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None
    if isinstance(doc.get("house"), dict) and doc["house"].get("topology") == "fmu":
        if overrides:
            raise ConfigError(f"{path}: overrides ({', '.join(overrides)}) apply to native houses only; "
                              "this house's plant is an FMU ([house] topology = \"fmu\")")
        return _fmu_house(doc, path, text)
    problems: list[str] = []
    for dotted, value in (overrides or {}).items():
        section, _, key = dotted.partition(".")
        if not key:
            problems.append(f"override {dotted!r}: expected 'section.key', e.g. 'storage.UA_loss'")
            continue
        doc.setdefault(section, {})[key] = value
    allowed = set(COMPONENTS) | {"house", "profiles", "connections"}
    for section in doc:
        if section not in allowed:
            close = get_close_matches(section, allowed, n=2)
            hint = f"did you mean [{'], ['.join(close)}]?" if close else f"allowed: {', '.join(sorted(allowed))}"
            problems.append(f"{path}:{_line(text, section)} [{section}]: unknown component; {hint}")
    house = doc.get("house", {})
    for key in ("name", "topology"):
        if key not in house:
            problems.append(f"{path}:{_line(text, 'house')} [house] {key}: missing; add e.g. "
                            f"{key} = \"{'two_generator_switch' if key == 'topology' else path.stem}\"")
    if house.get("topology", TOPOLOGIES[0]) not in TOPOLOGIES:
        problems.append(f"{path}:{_line(text, 'house', 'topology')} [house] topology = "
                        f"{house['topology']!r}: unknown; allowed: {', '.join(TOPOLOGIES)}, fmu")
    params = {}
    storage_fmu = None
    for section, cls in COMPONENTS.items():
        values = doc.get(section, {})
        if not isinstance(values, dict):
            problems.append(f"{path}:{_line(text, section)} {section}: must be a table [{section}]")
            continue
        if section == "storage":
            values = dict(values)
            storage_fmu = _storage_fmu(values, path, text, problems)
        try:
            params[section] = build_params(cls, values, f"[{section}]")
        except ConfigError as exc:
            for msg in str(exc).splitlines():
                key = msg.split("] ", 1)[1].split(" ", 1)[0] if "] " in msg else None
                problems.append(f"{path}:{_line(text, section, key)} {msg}")
    conn_values = doc.get("connections", {})
    conn_fields = {f.name for f in fields(Connections)}
    for key in conn_values:
        if key not in conn_fields:
            close = get_close_matches(key, conn_fields, n=2)
            problems.append(f"{path}:{_line(text, 'connections', key)} [connections] {key}: unknown; "
                            + (f"did you mean {', '.join(close)}?" if close else f"allowed: {', '.join(sorted(conn_fields))}"))
    connections = Connections(**{k: float(v) for k, v in conn_values.items() if k in conn_fields})
    vol = params["storage"].volume if "storage" in params else 0.8
    if not 0.0 <= connections.storage_inlet_mixing <= 0.5 * vol:
        problems.append(f"{path}:{_line(text, 'connections', 'storage_inlet_mixing')} [connections] "
                        f"storage_inlet_mixing = {connections.storage_inlet_mixing:g}: must be 0 … "
                        f"{0.5 * vol:g} m3 (half the storage volume)")
    for sec, top, bot in (("storage", "storage_top_port", "storage_bottom_port"),
                          ("dhw_storage", "dhw_draw_port", "dhw_cold_port"),
                          ("dhw_storage", "dhw_coil_top", "dhw_coil_bottom")):
        if sec in params:
            H = params[sec].height
            for key in (top, bot):
                v = getattr(connections, key)
                if not 0.0 <= v <= H:
                    problems.append(f"{path}:{_line(text, 'connections', key)} [connections] {key} = {v}: "
                                    f"outside the tank; allowed 0 … {H} m (the [{sec}] height)")
            if getattr(connections, top) < getattr(connections, bot):
                problems.append(f"{path}:{_line(text, 'connections', top)} [connections] {top} must be "
                                f"above {bot}")
    if storage_fmu is not None and "storage" in params:
        n = params["storage"].n_layers
        for key, want in (("storage_top_port", 0), ("storage_bottom_port", n - 1)):
            try:
                layer = storage.port_layer(getattr(connections, key), params["storage"])
            except ConfigError:
                continue  # reported above
            if layer != want:
                problems.append(f"{path}:{_line(text, 'connections', key)} [connections] {key}: the "
                                f"storage FMU has ports only in its top and bottom layers; this height "
                                f"is in layer {layer} of 0 … {n - 1}")
    prof = doc.get("profiles", {})
    typeday = prof.get("typeday", 0)
    if isinstance(typeday, bool) or not isinstance(typeday, int) or not 0 <= typeday <= 11:
        problems.append(f"{path}:{_line(text, 'profiles', 'typeday')} [profiles] typeday = {typeday!r}: "
                        "must be 0 (year 2021 series) or a type-day block 1 … 11")
        typeday = 0
    unknown = set(prof) - {"typeday", "household_kwh_per_year", "dhw_litres_per_day"}
    for key in sorted(unknown):
        problems.append(f"{path}:{_line(text, 'profiles', key)} [profiles] {key}: unknown; allowed: "
                        "household_kwh_per_year, dhw_litres_per_day, typeday")
    kwh = prof.get("household_kwh_per_year", 6500.0)
    litres = prof.get("dhw_litres_per_day", 300.0)
    for key, v, hi in (("household_kwh_per_year", kwh, 1e6), ("dhw_litres_per_day", litres, 1e5)):
        if not isinstance(v, (int, float)) or not 0 <= v <= hi:
            problems.append(f"{path}:{_line(text, 'profiles', key)} [profiles] {key} = {v!r}: "
                            f"must be a number 0 … {hi:g}")
    if problems:
        raise ConfigError("\n".join(problems))
    return HouseSpec(
        name=house["name"], path=path, description=house.get("description", ""),
        start=str(house.get("start", "2021-01-01")), household_kwh_per_year=float(kwh),
        dhw_litres_per_day=float(litres), typeday=typeday, params=params, connections=connections,
        storage_fmu=storage_fmu,
    )


# ------------------------------------------------------------------ the whole plant as an FMU
FMU_HOUSE_KEYS = {"name", "topology", "fmu", "description", "start", "solver", "step_size",
                  "relative_tolerance", "max_step"}


@dataclass(frozen=True)
class FmuHouseSpec:
    """A house whose whole plant is one FMU ([house] topology = "fmu"); see plant/fmu/house.py.

    bindings: catalogue signal -> (FMU variable, unit of the FMU variable or None = as declared).
    parameters: FMU variable -> (value, unit or None); value a number, boolean or string.
    solver: None = co-simulation; "CVode" / "Euler" = the model-exchange interface with that solver.
    max_step: each house step is split into equal FMU steps of at most this many seconds (None: one).
    """

    name: str
    path: Path
    description: str
    start: str
    fmu: Path
    bindings: dict
    parameters: dict
    solver: str | None = None
    step_size: float | None = None
    relative_tolerance: float = 1e-6
    max_step: float | None = None


def _fmu_house(doc: dict, path: Path, text: str) -> FmuHouseSpec:
    """Validate a house file whose plant is an FMU:

        [house]
        name = "house1"            # the device maps whose `house` is this name bind to it
        topology = "fmu"
        fmu = "house1.fmu"         # relative to this file
        start = "2021-01-10"       # optional, informational (recordings); the FMU has its own
        solver = "CVode"           # optional: use the model-exchange interface ("CVode" | "Euler")
        step_size = 1.0            #   Euler's fixed step [s]; relative_tolerance = 1e-6 for CVode
        max_step = 5.0             # optional: split each house step into FMU steps <= max_step s
        [bindings]                 # catalogue signal = "FMU variable" or { var = "...", unit = "K" }
        "boiler.U_set" = "boiler.U_set"
        "storage.T_sensor_1" = { var = "T_s1", unit = "K" }
        [parameters]               # FMU parameters: name = value or { value = ..., unit = "degC" }
        use_builtin_controller = false
    """
    from .catalogue import CATALOGUE
    from .fmu.component import SOLVERS, UNITS

    problems: list[str] = []
    house = doc["house"]
    for section in doc:
        if section not in ("house", "bindings", "parameters"):
            problems.append(f"{path}:{_line(text, section)} [{section}]: not used when the plant is an FMU "
                            "([house] topology = \"fmu\"); allowed: [house], [bindings], [parameters]")
    for key in house:
        if key not in FMU_HOUSE_KEYS:
            close = get_close_matches(key, FMU_HOUSE_KEYS, n=2)
            problems.append(f"{path}:{_line(text, 'house', key)} [house] {key}: unknown for an FMU plant; "
                            + (f"did you mean {', '.join(close)}?" if close else
                               f"allowed: {', '.join(sorted(FMU_HOUSE_KEYS))}"))
    name = house.get("name")
    if not isinstance(name, str) or not name:
        problems.append(f"{path}:{_line(text, 'house', 'name')} [house] name: missing; add e.g. name = \"house1\" "
                        "(device maps bind to the house of that name)")
    fmu = house.get("fmu")
    fmu_path = None
    where = f"{path}:{_line(text, 'house', 'fmu')} [house] fmu"
    if not isinstance(fmu, str) or not fmu:
        problems.append(f"{where} = {fmu!r}: topology \"fmu\" needs the path of the .fmu file (string)")
    else:
        fmu_path = Path(fmu) if Path(fmu).is_absolute() else path.parent / fmu
        if not fmu_path.is_file():
            problems.append(f"{where} = {fmu!r}: no such file ({fmu_path})")
    solver = house.get("solver")
    if solver is not None and solver not in SOLVERS:
        problems.append(f"{path}:{_line(text, 'house', 'solver')} [house] solver = {solver!r}: unknown; "
                        f"allowed: {', '.join(SOLVERS)} (leave it out for co-simulation)")
    numbers = {}
    for key in ("step_size", "relative_tolerance", "max_step"):
        v = house.get(key)
        if v is None:
            continue
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not v > 0:
            problems.append(f"{path}:{_line(text, 'house', key)} [house] {key} = {v!r}: must be a number > 0")
        else:
            numbers[key] = float(v)
    if solver == "Euler" and "step_size" not in numbers:
        problems.append(f"{path}:{_line(text, 'house', 'solver')} [house] solver = \"Euler\": needs "
                        "step_size = <fixed internal step in s>")
    if solver is None and ("step_size" in numbers or "relative_tolerance" in numbers):
        problems.append(f"{path}:{_line(text, 'house')} [house]: step_size / relative_tolerance apply to a "
                        "model-exchange solver only; add solver = \"CVode\" or \"Euler\"")
    bindings_doc = doc.get("bindings")
    bindings = {}
    if not isinstance(bindings_doc, dict) or not bindings_doc:
        problems.append(f"{path}:{_line(text, 'house')} [house] topology = \"fmu\": needs a [bindings] table "
                        "of catalogue signal = \"FMU variable\" (at least one)")
        bindings_doc = {}
    for signal, b in bindings_doc.items():
        loc = f"{path}:{_line(text, 'bindings', signal)} [bindings] {signal}"
        if signal not in CATALOGUE:
            close = get_close_matches(signal, CATALOGUE.names, n=3, cutoff=0.6)
            problems.append(f"{loc}: not a signal of the catalogue (plant/catalogue.py); "
                            + (f"did you mean {', '.join(close)}?" if close else "list them with `twin signals house1`"))
            continue
        if isinstance(b, str) and b:
            var, unit = b, None
        elif isinstance(b, dict) and set(b) <= {"var", "unit"} and isinstance(b.get("var"), str) \
                and isinstance(b.get("unit", ""), str):
            var, unit = b["var"], b.get("unit")
        else:
            problems.append(f"{loc} = {b!r}: expected \"FMU variable\" or {{ var = \"...\", unit = \"K\" }}")
            continue
        ours = CATALOGUE.signal(signal).unit
        if unit is not None and unit != ours and (unit not in UNITS or ours not in UNITS
                                                  or UNITS[unit][0] != UNITS[ours][0]):
            dim = UNITS[unit][0] if unit in UNITS else "unknown unit"
            problems.append(f"{loc}: unit mismatch, unit = {unit!r} ({dim}) cannot be converted to the "
                            f"signal's {ours!r} ({UNITS[ours][0] if ours in UNITS else 'no conversions'})")
            continue
        bindings[signal] = (var, unit)
    params = {}
    parameters = doc.get("parameters", {})
    if not isinstance(parameters, dict):
        problems.append(f"{path}:{_line(text, 'parameters')} parameters: must be a table [parameters]")
        parameters = {}
    for pname, v in parameters.items():
        loc = f"{path}:{_line(text, 'parameters', pname)} [parameters] {pname}"
        if isinstance(v, dict) and set(v) <= {"value", "unit"} and "value" in v:
            value, unit = v["value"], v.get("unit")
        else:
            value, unit = v, None
        if not isinstance(value, (bool, int, float, str)):
            problems.append(f"{loc} = {v!r}: expected a number, boolean, string or {{ value = 70.0, unit = \"degC\" }}")
            continue
        if unit is not None and unit not in UNITS:
            problems.append(f"{loc}: unit {unit!r} unknown; known: {', '.join(sorted(u for u in UNITS if u))}")
            continue
        params[pname] = (value, unit)
    if problems:
        raise ConfigError("\n".join(problems))
    return FmuHouseSpec(name=name, path=path, description=str(house.get("description", "")),
                        start=str(house.get("start", "")), fmu=fmu_path, bindings=bindings,
                        parameters=params, solver=solver, step_size=numbers.get("step_size"),
                        relative_tolerance=numbers.get("relative_tolerance", 1e-6),
                        max_step=numbers.get("max_step"))
