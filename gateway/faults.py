"""Fault scenarios: timed fault injections from a TOML file or the command line.

Scenario file:
    [[fault]]
    at = 600            # s of simulated time
    device = "chp_neotower2"
    kind = "trip"       # trip | sensor_open | sensor_drift | silent | late | drop | bad_crc | clear
                        # CAN (FMI-LS-BUS CAN terms, on the device's node): can_error_frame,
                        # can_error_passive, can_bus_off, can_recover
    point = "t_supply"  # sensor faults
    delta = 5.0         # sensor_drift offset in the point's unit; late: delay in s
    code = 0            # trip: fault code (default: the map's trip code)
Command line: --fault chp_neotower2:trip@600 (device:kind[:point[:delta]]@seconds).
Each injection goes through the Device's fault API, which records it as an event.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

from plant.errors import ConfigError

KINDS = ("trip", "sensor_open", "sensor_drift", "silent", "late", "drop", "bad_crc", "clear",
         "can_error_frame", "can_error_passive", "can_bus_off", "can_recover")


@dataclass(frozen=True)
class Fault:
    at: float
    device: str
    kind: str
    point: str = ""
    delta: float = 0.0
    code: int = 0

    def apply(self, devices: dict, transports=()) -> None:
        dev = devices[self.device]
        if self.kind.startswith("can_"):
            cans = [t for t in transports if getattr(t, "name", "") == "canopen"]
            if not cans:
                raise ConfigError(f"fault {self.kind} on {self.device}: no CANopen transport; add --can BUS")
            for t in cans:
                t.inject(self.kind[4:], node_id=dev.map.canopen.node_id)
        elif self.kind == "trip":
            dev.inject_trip(self.code or None)
        elif self.kind in ("sensor_open", "sensor_drift"):
            dev.inject_sensor_fault(self.point, self.kind.split("_")[1], self.delta)
        elif self.kind in ("silent", "late", "drop", "bad_crc"):
            dev.set_link_fault(self.kind, self.delta)
        else:
            dev.clear_faults()


def _check(f: Fault, where: str, devices: dict) -> None:
    if f.kind not in KINDS:
        raise ConfigError(f"{where}: kind = {f.kind!r}; allowed: {', '.join(KINDS)}")
    if f.device not in devices:
        raise ConfigError(f"{where}: device = {f.device!r}; devices: {', '.join(sorted(devices))}")
    if f.kind.startswith("sensor") and f.point not in devices[f.device].map:
        raise ConfigError(f"{where}: point = {f.point!r} is not a point of {f.device}")
    if f.at < 0:
        raise ConfigError(f"{where}: at = {f.at}; must be >= 0 s")


def parse_cli(spec: str, devices: dict) -> Fault:
    try:
        what, at = spec.rsplit("@", 1)
        parts = what.split(":")
        f = Fault(float(at), parts[0], parts[1], parts[2] if len(parts) > 2 else "",
                  float(parts[3]) if len(parts) > 3 else 0.0)
    except (ValueError, IndexError):
        raise ConfigError(f"--fault {spec!r}: expected device:kind[:point[:delta]]@seconds, "
                          "e.g. chp_neotower2:trip@600") from None
    _check(f, f"--fault {spec!r}", devices)
    return f


def load_scenario(path: str | Path, devices: dict) -> list[Fault]:
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ConfigError(f"{path}: cannot read scenario: {exc}") from None
    faults = []
    for i, raw in enumerate(doc.get("fault", [])):
        where = f"{path} [[fault]] #{i + 1}"
        unknown = set(raw) - {"at", "device", "kind", "point", "delta", "code"}
        if unknown:
            raise ConfigError(f"{where}: unknown keys {sorted(unknown)}; allowed: at, device, kind, point, delta, code")
        try:
            f = Fault(float(raw["at"]), str(raw["device"]), str(raw["kind"]), str(raw.get("point", "")),
                      float(raw.get("delta", 0.0)), int(raw.get("code", 0)))
        except KeyError as exc:
            raise ConfigError(f"{where}: missing {exc.args[0]!r}") from None
        _check(f, where, devices)
        faults.append(f)
    return sorted(faults, key=lambda f: f.at)
