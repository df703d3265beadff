"""House declarations: read a house file into named instances of kinds, check every link, report
every problem at once (file:line, key, the bad value, the closest valid names).

A house file has [house], [profiles] and one table per instance:

    [boiler]
    kind = "boiler"            # a kind of plant/kinds.py
    P_nom = 14000.0            # its parameters (the kind's Params) ...
    [switch]
    kind = "coupling_point"
    generators = ["boiler"]    # ... and its links (the kind's LINKS): instances, heights, tables

Overrides {"section.key": value} (or "section.table.key" inside an inline table) replace file
values before the checks, e.g. {"storage.UA_loss": 25.0, "switch.idle_flow.chp": 0.2}.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from pathlib import Path

from .component import REQUIRED, Instance, Link, build_params, is_number, link_problem, names_instances
from .errors import ConfigError, did_you_mean
from .housefile import HOUSES, line_of, read, resolve  # noqa: F401 (the names house files are found by)
HOUSE_KEYS = ("name", "description", "start", "base")
PROFILE_KEYS = ("household_kwh_per_year", "dhw_litres_per_day", "typeday", "dhw_series")
# what to do instead when a link names an instance of the wrong role
PUMP_HINT = {"emitter": "put a mixing station between it and the coupling point",
             "storage": "connect a storage through the point's storage key or a coil"}


@dataclass
class Declaration:
    name: str
    path: Path
    description: str
    start: str
    household_kwh_per_year: float
    dhw_litres_per_day: float
    typeday: int
    instances: dict
    problems: list
    prof: tuple = ()
    dhw_series: str = "SF1"


def _hint(bad: str, names, what: str) -> str:
    return did_you_mean(bad, names, f"{what}: {', '.join(sorted(names))}", cutoff=0.5)


def parse(doc: dict, path: Path, text: str, overrides: dict | None = None) -> Declaration:
    problems: list[str] = []
    _apply_overrides(doc, overrides, problems)
    house = doc.get("house", {})
    _check_house(house, path, text, problems)
    typeday, kwh, litres, dhw_series = _profiles(doc.get("profiles", {}), path, text, problems)
    instances: dict[str, Instance] = {}
    for order, (name, table) in enumerate(doc.items()):
        if name in ("house", "profiles"):
            continue
        inst = _instance(name, table, order, path, text, problems)
        if inst is not None:
            instances[name] = inst
    _check_links(instances, path, text, problems)
    decl = Declaration(name=house.get("name", path.stem), path=path,
                       description=str(house.get("description", "")),
                       start=str(house.get("start", "2021-01-01")),
                       household_kwh_per_year=float(kwh) if isinstance(kwh, (int, float)) else 0.0,
                       dhw_litres_per_day=float(litres) if isinstance(litres, (int, float)) else 0.0,
                       typeday=typeday, instances=instances, problems=problems, dhw_series=dhw_series)
    return decl


def _apply_overrides(doc: dict, overrides: dict | None, problems: list) -> None:
    for dotted, value in (overrides or {}).items():
        parts = dotted.split(".")
        if len(parts) < 2 or not isinstance(doc.get(parts[0], {}), dict):
            problems.append(f"override {dotted!r}: expected 'instance.key', e.g. 'storage.UA_loss'")
            continue
        target = doc.setdefault(parts[0], {})
        for part in parts[1:-1]:
            target = target.setdefault(part, {})
        target[parts[-1]] = value


def _check_house(house: dict, path: Path, text: str, problems: list) -> None:
    for key in house:
        if key not in HOUSE_KEYS:
            problems.append(f"{path}:{line_of(text, 'house', key)} [house] {key}: unknown; "
                            + _hint(key, HOUSE_KEYS, "allowed"))
    if "name" not in house:
        problems.append(f"{path}:{line_of(text, 'house')} [house] name: missing; add name = \"{path.stem}\"")


def _profiles(prof: dict, path: Path, text: str, problems: list) -> tuple:
    """(typeday, household kWh/year, DHW l/day, DHW series) of [profiles]; a bad typeday or series
    falls back to its default so the rest of the file is still checked."""
    for key in prof:
        if key not in PROFILE_KEYS:
            problems.append(f"{path}:{line_of(text, 'profiles', key)} [profiles] {key}: unknown; "
                            + _hint(key, PROFILE_KEYS, "allowed"))
    typeday = prof.get("typeday", 0)
    if isinstance(typeday, bool) or not isinstance(typeday, int) or not 0 <= typeday <= 11:
        problems.append(f"{path}:{line_of(text, 'profiles', 'typeday')} [profiles] typeday = {typeday!r}: "
                        "must be 0 (year 2021 series) or a type-day block 1 … 11")
        typeday = 0
    kwh = prof.get("household_kwh_per_year", 6500.0)
    litres = prof.get("dhw_litres_per_day", 300.0)
    for key, v, hi in (("household_kwh_per_year", kwh, 1e6), ("dhw_litres_per_day", litres, 1e5)):
        if not is_number(v) or not 0 <= v <= hi:
            problems.append(f"{path}:{line_of(text, 'profiles', key)} [profiles] {key} = {v!r}: "
                            f"must be a number 0 … {hi:g}")
    from profiles.loaders import DHW_SERIES

    dhw_series = prof.get("dhw_series", "SF1")
    if dhw_series not in DHW_SERIES:
        problems.append(f"{path}:{line_of(text, 'profiles', 'dhw_series')} [profiles] dhw_series = "
                        f"{dhw_series!r}: unknown; the shipped DHWcalc series: {', '.join(DHW_SERIES)}")
        dhw_series = "SF1"
    return typeday, kwh, litres, dhw_series


def _instance(name: str, table, order: int, path: Path, text: str, problems: list) -> Instance | None:
    """The instance of one table, or None when its kind is missing or unknown (nothing more of
    it can be checked)."""
    from .kinds import KINDS

    where = f"{path}:{line_of(text, name)} [{name}]"
    if not isinstance(table, dict):
        problems.append(f"{path}:{line_of(text, name)} {name}: must be a table [{name}] with a kind")
        return None
    kind = table.get("kind")
    if kind is None:
        problems.append(f"{where} kind: missing; add kind = \"...\" ("
                        + _hint(name, KINDS, "known kinds") + ")")
        return None
    if kind not in KINDS or kind == "profiles":
        problems.append(f"{path}:{line_of(text, name, 'kind')} [{name}] kind = {kind!r}: unknown; "
                        + _hint(kind, [k for k in KINDS if k != "profiles"], "known kinds"))
        return None
    k = KINDS[kind]
    values, options = _values_and_options(name, kind, k, table, where, path, text, problems)
    params = None
    if k.Params is not None:
        try:
            params = build_params(k.Params, values, f"[{name}]")
        except ConfigError as exc:
            for msg in str(exc).splitlines():
                key = msg.split("] ", 1)[1].split(" ", 1)[0] if "] " in msg else None
                problems.append(f"{path}:{line_of(text, name, key)} {msg}")
    return Instance(name, kind, params, options, where, order,
                    {key: line_of(text, name, key) for key in table})


def _values_and_options(name: str, kind: str, k, table: dict, where: str, path: Path, text: str,
                        problems: list) -> tuple[dict, dict]:
    """A table's keys sorted into parameter values and links; a missing required link is None,
    a missing optional one its default."""
    links = dict(k.LINKS)
    pnames = [f.name for f in fields(k.Params)] if k.Params else []
    values, options = {}, {}
    for key, v in table.items():
        if key == "kind":
            continue
        if key in links:
            options[key] = v
        elif key in pnames:
            values[key] = v
        else:
            problems.append(f"{path}:{line_of(text, name, key)} [{name}] {key}: not a parameter or link "
                            f"of a {kind}; " + _hint(key, pnames + list(links), "allowed"))
    for key, spec in links.items():
        if key not in options:
            if spec.default is REQUIRED:
                problems.append(f"{where} {key}: missing; a {kind} needs it ({spec.meaning})")
                options[key] = None
            else:
                options[key] = spec.default
    return values, options


def _check_links(instances: dict, path: Path, text: str, problems: list) -> None:
    """Every link of every instance by its type (plant/links.py), in its kind's LINKS order: the
    instances it names exist and have a role of its range, no port is used twice; then the
    kind's own check; then every generator and pumped consumer sits on a coupling point."""
    from .kinds import KINDS

    used: dict[tuple[str, str], str] = {}
    for inst in list(instances.values()):
        for key, spec in KINDS[inst.kind].LINKS.items():
            value = inst.options.get(key)
            if value is None and (spec.default is None or spec.default is REQUIRED or names_instances(spec)):
                continue  # not given where that is allowed, or missing and reported
            if names_instances(spec):
                _check_names(inst, key, spec, instances, used, path, text, problems)
                continue
            problem = link_problem(spec, value, inst.options)
            if problem:
                problems.append(f"{inst.at(key)} = {value!r}: {problem}")
                inst.options[key] = None if spec.default is REQUIRED else spec.default
        KINDS[inst.kind].check(inst, problems)
    for inst in instances.values():
        kind = KINDS[inst.kind]
        role = kind.role
        roles = kind.ROLES or (role,)
        if role in ("generator", "consumer") and not any((inst.name, r) in used for r in roles):
            problems.append(f"{inst.where}: a {inst.kind} connected to nothing; list it in a coupling "
                            f"point's {' or '.join(r + 's' for r in roles)}")
        if role == "emitter" and (inst.name, role) not in used:
            problems.append(f"{inst.where}: an emitter fed by nothing; name it as a mixing station's emitter")


def _check_names(inst: Instance, key: str, spec: Link, instances: dict, used: dict, path: Path,
                 text: str, problems: list) -> None:
    """A link naming instances: each exists and has a role of the link's range; a generator's,
    consumer's or emitter's port is named once. A bad name is dropped (a list keeps its good
    ones, so one bad name hides no other problem; a single one becomes None)."""
    from .kinds import KINDS

    v, roles = inst.options[key], spec.range
    names = list(v) if isinstance(v, (list, tuple)) else [v]
    if not all(isinstance(n, str) for n in names) or (spec.type is Instance and not isinstance(v, str)):
        problems.append(f"{path}:{line_of(text, inst.name, key)} [{inst.name}] {key} = {v!r}: "
                        "expected instance name(s) (strings)")
        inst.options[key] = None
        return
    if spec.type == list[Instance] and isinstance(v, str):
        # a kind iterates a list link: a bare name would be read letter by letter. Reported, and
        # checked on as the one-name list it means, so nothing else is reported for it
        problems.append(f"{path}:{line_of(text, inst.name, key)} [{inst.name}] {key} = {v!r}: "
                        f"a list of instance names; write {key} = [{v!r}]".replace("'", '"'))
        inst.options[key] = [v]
    bad = False
    keep = []
    for n in names:
        loc = f"{path}:{line_of(text, inst.name, key)} [{inst.name}] {key} = {n!r}"
        if n not in instances:
            problems.append(f"{loc}: no such instance; " + _hint(n, instances, "declared"))
            bad = True
            continue
        other = KINDS[instances[n].kind]
        role = next((r for r in roles if r in other.ROLES or other.role == r), None)
        if role is None:
            hint = PUMP_HINT.get(other.role, f"a {' or '.join(roles)} is needed here")
            if key == "consumers":
                hint = f"a {instances[n].kind} has no pump of its own: " + PUMP_HINT.get(other.role, hint)
            problems.append(f"{loc}: a {instances[n].kind} ({other.role}) cannot be used as {key}; {hint}")
            bad = True
            continue
        if role in ("generator", "consumer", "emitter"):
            if (n, role) in used:
                problems.append(f"{loc}: port connected twice (also by [{used[(n, role)]}])")
                continue
            used[(n, role)] = inst.name
        keep.append(n)
    if isinstance(v, (list, tuple)):
        inst.options[key] = keep
    elif bad:
        inst.options[key] = None


def load(name_or_path: str | Path, overrides: dict | None = None) -> Declaration:
    path = resolve(name_or_path)
    return parse(read(path), path, path.read_text(), overrides)


def params_of(name_or_path: str | Path, instance: str, overrides: dict | None = None):
    """The Params of one instance exactly as load(name_or_path, overrides) gives them, without
    building and checking the rest of the house: an emitter replayed alone asks for its own
    ~800 times per diagnosis (loading the whole house for them was about 1 ms of each 4-5 ms replay).
    overrides: {"instance.key": value}; those of other instances are ignored. Values that give no
    Params (out of range, not a number) raise a ConfigError naming them."""
    path = resolve(name_or_path)
    doc = read(path)
    if instance not in doc:
        raise ConfigError(f"{path}: no instance {instance!r}")
    own = {k: v for k, v in (overrides or {}).items() if k.split(".", 1)[0] == instance}
    _apply_overrides(doc, own, [])
    problems: list[str] = []
    inst = _instance(instance, doc[instance], 0, path, path.read_text(), problems)
    if problems and (inst is None or inst.params is None):
        raise ConfigError("\n".join(problems))
    if inst.params is None:
        raise ConfigError(f"{path} [{instance}]: a {inst.kind} has no parameters")
    return inst.params
