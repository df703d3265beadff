"""The CANopen face of a bench map: each point's object and the PDOs they travel in, derived
from the map's directions, never written by hand.

`pdo_layout(bench)` is the one place the mapping is computed; the bench emulator's node
(`twin bench NAME --canopen BUS`, phil/emulator/server.py) serves the object dictionary built
from `canopen_map(bench)` by the gateway's builder (gateway/transports/canopen_od.py), and the
twin's CanopenLink (phil/canopen_link.py) checks the bench's PDOs against the same layout.

  set-points   (to_bench, writable)  objects 0x2200 sub 1, 2 ... in map order, in the bench's
                                     RPDOs (the twin transmits them)
  measurements (from_bench)          objects 0x2100 sub 1, 2 ... in map order, in the bench's
                                     TPDOs (the bench transmits them)

Points fill PDOs in map order, a new PDO when the next point would pass the 64 bits of one
CAN frame: two float32 or uint32 per PDO, four int16. Map order keeps a bench's heat meter and
the clock it is read with (listed last) in one frame where they fit. CiA 301's pre-defined
connection set has four PDOs per direction; a map needing more is refused, naming the map.
A point may name its own `co_index`/`co_sub` (kept); a `pdo` tag on a bench point is refused.
"""
from __future__ import annotations

import dataclasses
from dataclasses import dataclass

from gateway.maps.model import Point
from gateway.transports.canopen_od import N_PDO, pdo_bits
from phil.benchmap import BenchMap
from plant.errors import DeviceMapError

#: manufacturer-area records of the two directions (device-interfaces §2.7: commands, measurements)
SETPOINT_INDEX, MEASUREMENT_INDEX = 0x2200, 0x2100
FRAME_BITS = 64


@dataclass(frozen=True)
class Pdo:
    """One PDO of the bench: `kind` R (the bench receives: set-points) or T (it transmits:
    measurements), its number 1…4, and the points it carries in frame order."""

    kind: str
    number: int
    points: tuple[str, ...]

    @property
    def name(self) -> str:
        return f"{self.kind}PDO{self.number}"

    def cob_id(self, node_id: int) -> int:
        """Its COB-ID in the pre-defined connection set (CiA 301)."""
        return (0x200 if self.kind == "R" else 0x180) + 0x100 * (self.number - 1) + node_id


def _pack(bench: BenchMap, kind: str, points: list[Point]) -> tuple[Pdo, ...]:
    runs: list[list[Point]] = []
    for p in points:
        if not runs or sum(pdo_bits(q) for q in runs[-1]) + pdo_bits(p) > FRAME_BITS:
            runs.append([])
        runs[-1].append(p)
    if len(runs) > N_PDO:
        what = "set-points" if kind == "R" else "measurements"
        bits = sum(pdo_bits(p) for p in points)
        raise DeviceMapError(
            f"{bench.dmap.path}: its {len(points)} {what} ({bits} bits) need {len(runs)} "
            f"{kind}PDOs; CiA 301's pre-defined connection set has {N_PDO} per direction, so "
            f"bench {bench.id} cannot exchange over CANopen; use smaller types (int16 with a scale) "
            "or fewer points, or exchange over Modbus TCP")
    return tuple(Pdo(kind, n, tuple(p.name for p in run)) for n, run in enumerate(runs, 1))


def pdo_layout(bench: BenchMap) -> tuple[Pdo, ...]:
    """The bench's RPDOs then TPDOs, computed from its map (see the module text)."""
    dmap = bench.dmap
    tagged = [p.name for p in dmap.points if p.pdo is not None]
    if tagged:
        raise DeviceMapError(f"{dmap.path} [point {tagged[0]}] pdo = {dmap.point(tagged[0]).pdo!r}: a bench "
                             "map's PDOs are derived from each point's direction (phil/pdo_layout.py); "
                             f"remove 'pdo' from {', '.join(tagged)}")
    setpoints = [dmap.point(i.name) for i in bench.setpoints() if dmap.point(i.name).writable]
    measurements = [dmap.point(i.name) for i in bench.measurements()]
    return _pack(bench, "R", setpoints) + _pack(bench, "T", measurements)


def canopen_map(bench: BenchMap) -> BenchMap:
    """The bench map with every exchanged point's object and PDO filled in, for the object
    dictionary builder (gateway/transports/canopen_od.py) and the map's table and EDS export."""
    tag = {name: f"{pdo.kind}{pdo.number}" for pdo in pdo_layout(bench) for name in pdo.points}
    subs = {SETPOINT_INDEX: 0, MEASUREMENT_INDEX: 0}
    points = []
    for p in bench.dmap.points:
        if p.name not in tag:
            points.append(p)
            continue
        index = SETPOINT_INDEX if tag[p.name].startswith("R") else MEASUREMENT_INDEX
        subs[index] += 1
        if p.co_index is None:
            p = dataclasses.replace(p, co_index=index, co_sub=subs[index])
        points.append(dataclasses.replace(p, pdo=tag[p.name]))
    dmap = dataclasses.replace(bench.dmap, points=tuple(points), _by_name={})
    return dataclasses.replace(bench, dmap=dmap)
