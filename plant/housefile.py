"""House files on disk: find one by name or path, read it (a variant laid over its base), and
the line of a table or key for messages."""
from __future__ import annotations

import re
from functools import lru_cache
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from .errors import ConfigError, closest

HOUSES = Path(__file__).parent / "houses"
# the CoSES laboratory's names of the five houses (reference §12), accepted wherever a house is named
ALIASES = {"SF1": "house1", "SF2": "house2", "SF3": "house3", "SF4": "house4", "MF5": "house5"}
#: TOML files beside the house files that are not houses: <house>_sil.toml, the SiL signal list of
#: reference §13.1 as a columns file (profiles/columns.py)
NOT_HOUSES = ("_sil",)


def shipped() -> list[str]:
    """Names of the shipped house files, variants included (not the SiL lists beside them)."""
    return sorted(f.stem for f in HOUSES.glob("*.toml") if not f.stem.endswith(NOT_HOUSES))


def alias_of(name: str) -> str | None:
    """The laboratory's name of a shipped house (house2 -> SF2), or None."""
    return next((a for a, n in ALIASES.items() if n == name), None)


def resolve(name_or_path: str | Path) -> Path:
    p = Path(name_or_path)
    if p.suffix == ".toml" or p.exists():
        if not p.exists():
            raise ConfigError(f"{p}: no such house file")
        return p
    name_or_path = ALIASES.get(str(name_or_path).upper(), name_or_path)
    candidate = HOUSES / f"{name_or_path}.toml"
    if not candidate.exists() or candidate.stem.endswith(NOT_HOUSES):
        known = shipped()
        raise ConfigError(f"house {name_or_path!r}: not found; shipped houses: {', '.join(known)} "
                          f"(laboratory names: {', '.join(ALIASES)})")
    return candidate


def line_of(text: str, section: str, key: str | None = None) -> int:
    """Line number of [section] (or of key inside it) in the TOML text; 0 when not found."""
    start, keys = _line_index(text).get(section, (0, {}))
    return start if key is None else keys.get(key, start)


@lru_cache(maxsize=16)
def _line_index(text: str) -> dict:
    """{section: (line of its first header, {key: line of its first assignment in that table})}:
    one pass over the text (a house is parsed again for every replay's overrides)."""
    index, keys = {}, None
    for i, line in enumerate(text.splitlines(), 1):
        if re.match(r"^\s*\[", line):
            m = re.match(r"^\s*\[([^\[\]]*)\]\s*(#.*)?$", line)
            keys = None
            if m and m.group(1) not in index:
                keys = {}
                index[m.group(1)] = (i, keys)
            continue
        if keys is not None:
            m = re.match(r"""^\s*(?:"([^"]*)"|'([^']*)'|([^\s="']+))\s*=""", line)
            if m:
                keys.setdefault(next(g for g in m.groups() if g is not None), i)
    return index


@lru_cache(maxsize=64)
def _parsed(path: Path, mtime_ns: int, size: int) -> dict:
    try:
        return tomllib.loads(path.read_text())
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError(f"{path}: not valid TOML: {exc}") from None


def _copy(value):
    """A parsed TOML document's copy: its tables and arrays new, its values (str, numbers, bools,
    dates: all immutable) shared. copy.deepcopy gives the same and took a tenth of loading a
    house, replayed ~500 times per diagnosis."""
    if isinstance(value, dict):
        return {k: _copy(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_copy(v) for v in value]
    return value


def read(path: Path, _seen: tuple = ()) -> dict:
    """The file's tables; a file with [house] base = "other" is that house with these tables'
    keys laid over it (a variant: a finer truth, a cut, another generator).

    Parsed once per version of the file (its modification time and size) and copied: a diagnosis
    loads the same house for each of its ~500 replays, and parsing its TOML took 8 % of it."""
    st = path.stat()
    doc = _copy(_parsed(path, st.st_mtime_ns, st.st_size))
    base = doc.get("house", {}).get("base") if isinstance(doc.get("house"), dict) else None
    if base is None:
        return doc
    base_path = resolve(base) if not str(base).endswith(".toml") else path.parent / base
    if base_path.resolve() in _seen or base_path.resolve() == path.resolve():
        raise ConfigError(f"{path}: [house] base = {base!r}: a house cannot be its own base")
    merged = read(base_path, _seen + (path.resolve(),))
    for name in doc["house"].get("remove", []):
        if name not in merged or name in ("house", "profiles"):
            raise ConfigError(f"{path}: [house] remove = {name!r}: the base {base!r} declares no such "
                              "instance; " + ", ".join(closest(name, [k for k in merged if k not in ("house", "profiles")])
                                          or [k for k in merged if k not in ("house", "profiles")]))
        del merged[name]
    for name, table in doc.items():
        if isinstance(table, dict) and isinstance(merged.get(name), dict):
            merged[name] = {**merged[name], **table}
        else:
            merged[name] = table
    merged["house"].pop("base", None)
    merged["house"].pop("remove", None)
    return merged
