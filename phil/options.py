"""What a PHIL run is told: the options of `twin phil`, the house's PHIL variant and where each
bench's PLC is (polled, served, or a CANopen node), parsed from the command line's --bench."""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from gateway.transports.can_bus import parse_bus_spec
from plant.errors import ConfigError, TransportError

#: the PHIL variant of each house, by its name and its laboratory name (plant/houses/house<N>_phil.toml)
HOUSE_FILES = {**{f"house{n}": f"house{n}_phil" for n in range(1, 6)},
               **{alias: f"house{n}_phil" for n, alias in enumerate(("SF1", "SF2", "SF3", "SF4", "MF5"), 1)}}



@dataclass
class PhilOptions:
    speed: float = 1.0
    dt: float = 1.0
    hours: float = 24.0
    typeday: int = 0
    record: str | Path | None = None
    stale_s: float | None = None      # wall seconds; default: each bench map's [phil]
    stop_s: float | None = None
    timeout_s: float = 0.5
    retries: int = 1
    stop_file: str | Path | None = None
    warmup_s: float = 600.0           # simulated s before the run proper: benches and house settle
    retry_s: float = 1.0              # a bench whose exchange failed is tried again after this (wall s);
                                      # meanwhile its measurements are held, the others keep their pace
    served_age_s: float = 2.0         # served benches: a measurement not written this long (wall) is silent
    pdo_age_s: float = 2.0            # CANopen benches: a measurement whose TPDO is this old (wall) is silent
    start_h: float = 0.0              # hour of the profiles (type-day block) the warm-up starts at;
                                      # the house gets there unpaced on ideal benches
    district: str = "coses"           # the grid bench: the district file whose grid is simulated
                                      # (the house at its node there, phil/grid.py)
    others: str = "all"               # the grid bench: "all" the district's other houses simulated on
                                      # the grid, "none" only the PHIL house draws
    phase_s: float | None = None      # wall s after each whole cycle of the system clock at which the
                                      # steps start (a lab house on its own clock); None: one cycle
                                      # after the run starts (gateway/clock.py PacedClock)



def house_file(house: str) -> str:
    """The PHIL variant of a house (house1 -> plant/houses/house1_phil.toml), or a path as is."""
    if house.endswith(".toml"):
        return house
    if house not in HOUSE_FILES:
        raise ConfigError(f"twin phil {house}: no PHIL variant; known: {', '.join(sorted(HOUSE_FILES))}")
    return HOUSE_FILES[house]


@dataclass(frozen=True)
class BenchAddress:
    """Where a bench's PLC is: polled there (the twin as Modbus TCP master), served there
    (`serve`: the twin as the server the PLC reads set-points from and writes measurements to),
    or a CANopen node on the python-can bus `bus` (the twin as master, by PDO)."""

    host: str
    port: int
    serve: bool = False
    bus: str = ""

    def __str__(self) -> str:
        if self.bus:
            return f"canopen:{self.bus}"
        return f"{'serve:' if self.serve else ''}{self.host}:{self.port}"


def parse_bench(spec: str) -> tuple[str, BenchAddress]:
    """'NAME=HOST:PORT' (poll the bench PLC), 'NAME=serve:HOST:PORT' (serve it) or
    'NAME=canopen:BUS' (its CANopen node on a bus spec, gateway/transports/can_bus.py)."""
    name, _, address = spec.partition("=")
    if name and address.startswith("canopen:"):
        bus = address.removeprefix("canopen:")
        try:
            parse_bus_spec(bus)
        except TransportError as exc:
            raise ConfigError(f"--bench {spec!r}: {exc}; e.g. brine=canopen:virtual:lab") from None
        return name, BenchAddress("", 0, bus=bus)
    serve = address.startswith("serve:")
    host, _, port = address.removeprefix("serve:").rpartition(":")
    if not name or not port.isdigit():
        raise ConfigError(f"--bench {spec!r}: expected NAME=HOST:PORT (the twin polls the bench PLC), "
                          "NAME=serve:HOST:PORT (the PLC polls the twin) or NAME=canopen:BUS (its CANopen "
                          "node), e.g. space_heating=127.0.0.1:5031")
    return name, BenchAddress(host or "127.0.0.1", int(port), serve)
