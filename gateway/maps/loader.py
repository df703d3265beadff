"""Device maps from files: a TOML map or a CSV register table, chosen by the file's suffix."""
from __future__ import annotations

from pathlib import Path

from .csv_table import load_csv
from .model import DEVICES_DIR, DeviceMap, load_toml, map_path

__all__ = ["DEVICES_DIR", "load_all", "load_map"]


def load_map(path: str | Path) -> DeviceMap:
    """Load and check one map (a device id, a .toml or a .csv path); one DeviceMapError lists
    every problem."""
    path = Path(path)
    if not path.suffix:
        path = map_path(str(path))
    return load_csv(path) if path.suffix.lower() == ".csv" else load_toml(path)


def load_all(directory: Path | None = None) -> dict[str, DeviceMap]:
    """Every map in `directory`, by device id, in file-name order."""
    directory = directory or DEVICES_DIR
    return {p.stem: load_map(p) for p in sorted(directory.glob("*.toml"))}
