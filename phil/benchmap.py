"""Bench maps: one PHIL emulator bench's bus face, a device map plus what PHIL needs per point.

A bench map is a device map (devices/README.md: same sections, same loader, lint, codec and
CSV/MD export, gateway/maps/) whose points carry three more fields, and a `[phil]` section:

| field | meaning |
|---|---|
| `direction` | `to_bench` (a set-point the twin sends) or `from_bench` (a value the bench measured) |
| `rate_limit` | set-points: largest change the twin sends per second, in `unit`/s |
| `safe` | set-points: the value the twin sends on a fault and at a stop, in `unit` |

`[phil]`: `stale_s` (a measurement with no fresh value this long is rejected and held),
`stop_s` (rejected this long: safe set-points and stop), `serve_offset` (when the twin serves
the bench PLC, phil/served.py: the holding address where the PLC writes a measurement is
serve_offset + its input address; default 100). Point names are the reference's §13.2
signal names (STM_HCVLaM_Set_degC ...); `command`/`signal` bind them to the bench emulator's own
model (phil/emulator/), which is what a bench PLC's program would be.

Loading reports every problem at once as one DeviceMapError, each line
'<file> [point NAME] key = value: what is wrong; fix'.
"""
from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path

from gateway.maps.lint import lint_map
from gateway.maps.model import DeviceMap, build_map
from plant.errors import DeviceMapError, closest

#: Where the shipped bench maps live.
MAPS_DIR = Path(__file__).resolve().parent / "maps"
DIRECTIONS = ("to_bench", "from_bench")
BENCH_KEYS = ("direction", "rate_limit", "safe")


@dataclass(frozen=True)
class Interface:
    """What PHIL adds to one point: its direction, rate limit and safe value (device units)."""

    name: str
    direction: str
    rate_limit: float | None = None
    safe: float | None = None


@dataclass(frozen=True)
class BenchMap:
    """A bench's device map, its interfaces in map order, and its staleness limits [s]."""

    dmap: DeviceMap
    interfaces: tuple[Interface, ...]
    stale_s: float = 5.0
    stop_s: float = 30.0
    serve_offset: int = 100

    @property
    def id(self) -> str:
        return self.dmap.id

    def setpoints(self) -> tuple[Interface, ...]:
        return tuple(i for i in self.interfaces if i.direction == "to_bench")

    def measurements(self) -> tuple[Interface, ...]:
        return tuple(i for i in self.interfaces if i.direction == "from_bench")

    def interface(self, name: str) -> Interface:
        for i in self.interfaces:
            if i.name == name:
                return i
        close = closest(name, [i.name for i in self.interfaces], n=3)
        raise DeviceMapError(f"{self.dmap.path}: no interface {name!r}; closest: {', '.join(close) or 'none'}")


def bench_map_path(name: str | Path) -> Path:
    """A bench id (file stem in phil/maps/) or a path to a bench map."""
    path = Path(name)
    if path.suffix == ".toml":
        return path
    path = MAPS_DIR / f"{name}.toml"
    if not path.exists():
        known = sorted(p.stem for p in MAPS_DIR.glob("*.toml"))
        raise DeviceMapError(f"{path}: no such bench map; known: {', '.join(known)}")
    return path


def shipped() -> list[str]:
    return sorted(p.stem for p in MAPS_DIR.glob("*.toml"))


def load_bench_map(name: str | Path) -> BenchMap:
    """Load and lint one bench map; one DeviceMapError names every problem (file, key, fix)."""
    path = bench_map_path(name)
    try:
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise DeviceMapError(f"{path}: cannot read bench map ({exc}); fix the TOML syntax") from exc
    raw_points = doc.get("map", {}).get("points", []) + doc.get("point", [])
    problems: list[str] = []
    extras = [{k: p.pop(k) for k in BENCH_KEYS if k in p} for p in raw_points]
    doc = {**doc, "map": {"points": raw_points}, "point": []}
    dmap = None
    try:
        dmap = build_map(path, doc, problems)
    except (KeyError, TypeError, ValueError) as exc:
        problems.append(f"{path}: malformed entry ({exc!r}); see phil/benchmap.py for the fields")
    if dmap is not None:
        problems += [p.text for p in lint_map(dmap) if p.level == "error"]
    interfaces = tuple(_interface(path, raw, extra, problems) for raw, extra in zip(raw_points, extras))
    section = doc.get("phil", {})
    stale_s, stop_s = float(section.get("stale_s", 5.0)), float(section.get("stop_s", 30.0))
    if not 0 < stale_s < stop_s:
        problems.append(f"{path} [phil] stale_s = {stale_s}, stop_s = {stop_s}: need 0 < stale_s < stop_s; "
                        "a measurement is first held, then the run stops")
    offset = section.get("serve_offset", 100)
    if dmap is not None:
        problems += _serve_offset_problems(path, dmap, interfaces, offset)
    if problems or dmap is None:
        raise DeviceMapError("\n".join(dict.fromkeys(problems)))
    return BenchMap(dmap=dmap, interfaces=interfaces, stale_s=stale_s, stop_s=stop_s, serve_offset=offset)


def _serve_offset_problems(path: Path, dmap: DeviceMap, interfaces: tuple[Interface, ...], offset: object) -> list[str]:
    """serve_offset must put every measurement's served holding register above the set-points'."""
    if isinstance(offset, bool) or not isinstance(offset, int) or not 0 < offset <= 60000:
        return [f"{path} [phil] serve_offset = {offset!r}: must be an integer 1…60000 (holding address "
                "of the served measurements = serve_offset + input address)"]
    names = {i.name for i in interfaces if i.direction == "to_bench"}
    top = max((p.address + p.words for p in dmap.points if p.name in names and p.table == "holding"), default=0)
    if offset < top:
        return [f"{path} [phil] serve_offset = {offset}: below the set-points' holding registers (up to "
                f"{top - 1}); the served measurements would overlap them; use serve_offset >= {top}"]
    return []


def _interface(path: Path, raw: dict, extra: dict, problems: list[str]) -> Interface:
    """The PHIL fields of one point, checked against its device-map fields."""
    name = raw.get("name", "?")
    where = f"{path} [point {name}]"
    direction = extra.get("direction")
    access = raw.get("access", "R")
    rng = raw.get("range")
    if direction is None:
        problems.append(f"{where}: missing key 'direction'; add direction = 'to_bench' (a set-point) "
                        "or 'from_bench' (a measurement)")
    elif direction not in DIRECTIONS:
        close = closest(str(direction), DIRECTIONS, n=1)
        problems.append(f"{where} direction = {direction!r}: must be one of {', '.join(DIRECTIONS)}"
                        + (f" (closest: {close[0]})" if close else ""))
    if direction == "from_bench" and access != "R":
        problems.append(f"{where} access = {access!r}: a measured value (direction = 'from_bench') "
                        "must not be writable; set access = 'R'")
    if direction == "from_bench" and ("rate_limit" in extra or "safe" in extra):
        problems.append(f"{where}: rate_limit/safe on a measured value; they belong to set-points "
                        "(direction = 'to_bench'); remove them")
    if direction == "to_bench" and access == "R":
        problems.append(f"{where} access = 'R': a set-point (direction = 'to_bench') must be writable; "
                        "set access = 'RW'")
    if direction in (None, "from_bench") or direction not in DIRECTIONS:
        return Interface(name, str(direction))
    rate, safe = extra.get("rate_limit"), extra.get("safe")
    if not isinstance(rate, (int, float)) or isinstance(rate, bool) or not rate > 0:
        problems.append(f"{where} rate_limit = {rate!r}: a set-point needs a rate limit > 0 in "
                        f"{raw.get('unit', 'its unit')}/s; add rate_limit = ...")
        rate = None
    if not isinstance(safe, (int, float)) or isinstance(safe, bool) or math.isnan(safe):
        problems.append(f"{where} safe = {safe!r}: a set-point needs the safe value sent on a fault; "
                        "add safe = ... within its range")
        safe = None
    elif rng is not None and len(rng) == 2 and rng[0] <= rng[1] and not rng[0] <= safe <= rng[1]:
        problems.append(f"{where} safe = {safe!r}: outside range [{rng[0]}, {rng[1]}] "
                        f"{raw.get('unit', '')}; choose a safe value inside the range")
    if rng is None:
        problems.append(f"{where}: set-point without range; add range = [low, high] "
                        "(the twin clamps every set-point to it)")
    return Interface(name, direction, float(rate) if rate else None, float(safe) if safe is not None else None)


def lint_bench_maps(names: list[str] | None = None) -> list[str]:
    """Problems of every named (default: every shipped) bench map, one line each."""
    out: list[str] = []
    for name in names or shipped():
        try:
            load_bench_map(name)
        except DeviceMapError as exc:
            out += str(exc).splitlines()
    return out
