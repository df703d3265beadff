"""House files whose whole plant is one FMU ([house] topology = "fmu"): syntax and checks.

The FmuHouse (plant/fmu/house.py) serves such a plant with the House API; every problem of the
file is reported at once, with file:line, key and the fix.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..component import is_number
from ..housefile import line_of, read
from ..errors import ConfigError, did_you_mean


def load(path: Path) -> "FmuHouseSpec":
    return _fmu_house(read(path), path, path.read_text())


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
    problems: list[str] = []
    house = doc["house"]
    _check_sections_and_keys(doc, house, path, text, problems)
    name = house.get("name")
    if not isinstance(name, str) or not name:
        problems.append(f"{path}:{line_of(text, 'house', 'name')} [house] name: missing; add e.g. name = \"house1\" "
                        "(device maps bind to the house of that name)")
    fmu_path = _fmu_path(house, path, text, problems)
    solver, numbers = _solver(house, path, text, problems)
    bindings = _bindings(doc, path, text, problems)
    params = _parameters(doc, path, text, problems)
    if problems:
        raise ConfigError("\n".join(problems))
    return FmuHouseSpec(name=name, path=path, description=str(house.get("description", "")),
                        start=str(house.get("start", "")), fmu=fmu_path, bindings=bindings,
                        parameters=params, solver=solver, step_size=numbers.get("step_size"),
                        relative_tolerance=numbers.get("relative_tolerance", 1e-6),
                        max_step=numbers.get("max_step"))


def _check_sections_and_keys(doc: dict, house: dict, path: Path, text: str, problems: list) -> None:
    for section in doc:
        if section not in ("house", "bindings", "parameters"):
            problems.append(f"{path}:{line_of(text, section)} [{section}]: not used when the plant is an FMU "
                            "([house] topology = \"fmu\"); allowed: [house], [bindings], [parameters]")
    for key in house:
        if key not in FMU_HOUSE_KEYS:
            problems.append(f"{path}:{line_of(text, 'house', key)} [house] {key}: unknown for an FMU plant; "
                            + did_you_mean(key, FMU_HOUSE_KEYS, f"allowed: {', '.join(sorted(FMU_HOUSE_KEYS))}", n=2))


def _fmu_path(house: dict, path: Path, text: str, problems: list) -> Path | None:
    """The .fmu file, relative to the house file unless absolute; None when it is not a string."""
    fmu = house.get("fmu")
    fmu_path = None
    where = f"{path}:{line_of(text, 'house', 'fmu')} [house] fmu"
    if not isinstance(fmu, str) or not fmu:
        problems.append(f"{where} = {fmu!r}: topology \"fmu\" needs the path of the .fmu file (string)")
    else:
        fmu_path = Path(fmu) if Path(fmu).is_absolute() else path.parent / fmu
        if not fmu_path.is_file():
            problems.append(f"{where} = {fmu!r}: no such file ({fmu_path})")
    return fmu_path


def _solver(house: dict, path: Path, text: str, problems: list) -> tuple:
    """(solver, {step_size, relative_tolerance, max_step: the valid ones as floats})."""
    from .component import SOLVERS

    solver = house.get("solver")
    if solver is not None and solver not in SOLVERS:
        problems.append(f"{path}:{line_of(text, 'house', 'solver')} [house] solver = {solver!r}: unknown; "
                        f"allowed: {', '.join(SOLVERS)} (leave it out for co-simulation)")
    numbers = {}
    for key in ("step_size", "relative_tolerance", "max_step"):
        v = house.get(key)
        if v is None:
            continue
        if not is_number(v) or not v > 0:
            problems.append(f"{path}:{line_of(text, 'house', key)} [house] {key} = {v!r}: must be a number > 0")
        else:
            numbers[key] = float(v)
    if solver == "Euler" and "step_size" not in numbers:
        problems.append(f"{path}:{line_of(text, 'house', 'solver')} [house] solver = \"Euler\": needs "
                        "step_size = <fixed internal step in s>")
    if solver is None and ("step_size" in numbers or "relative_tolerance" in numbers):
        problems.append(f"{path}:{line_of(text, 'house')} [house]: step_size / relative_tolerance apply to a "
                        "model-exchange solver only; add solver = \"CVode\" or \"Euler\"")
    return solver, numbers


def _bindings(doc: dict, path: Path, text: str, problems: list) -> dict:
    """[bindings]: catalogue signal -> (FMU variable, its unit or None), the valid entries only."""
    from ..catalogue import CATALOGUE
    from .component import UNITS

    bindings_doc = doc.get("bindings")
    bindings = {}
    if not isinstance(bindings_doc, dict) or not bindings_doc:
        problems.append(f"{path}:{line_of(text, 'house')} [house] topology = \"fmu\": needs a [bindings] table "
                        "of catalogue signal = \"FMU variable\" (at least one)")
        bindings_doc = {}
    for signal, b in bindings_doc.items():
        loc = f"{path}:{line_of(text, 'bindings', signal)} [bindings] {signal}"
        if signal not in CATALOGUE:
            problems.append(f"{loc}: not a signal of the catalogue (plant/catalogue.py); "
                            + did_you_mean(signal, CATALOGUE.names, "list them with `twin signals house1`"))
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
    return bindings


def _parameters(doc: dict, path: Path, text: str, problems: list) -> dict:
    """[parameters]: FMU variable -> (value, unit or None), the valid entries only."""
    from .component import UNITS

    params = {}
    parameters = doc.get("parameters", {})
    if not isinstance(parameters, dict):
        problems.append(f"{path}:{line_of(text, 'parameters')} parameters: must be a table [parameters]")
        parameters = {}
    for pname, v in parameters.items():
        loc = f"{path}:{line_of(text, 'parameters', pname)} [parameters] {pname}"
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
    return params
