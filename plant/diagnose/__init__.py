"""`twin diagnose`: find the missing physics behind the mismatch between a recording and the twin.

    from plant.diagnose import diagnose, recording_io
    rec = recording_io.load("lab.csv", "columns.toml")
    report = diagnose(rec, house="house1", out="report/")     # dict, also report/report.json

Stages (pipeline.py, each a function returning an immutable value): prepare and replay
(replay.py) -> calibrate (calibration.py) -> locate (locate.py) -> fit the candidates (effects/,
fit.py) -> judge and select (verdict.py, forward.py, search.py) -> report (report.py). Method and
report.json schema: docs/diagnose.md.
"""
from __future__ import annotations

from . import recording_io  # noqa: F401  (the loader beside diagnose, as the example above uses it)
from .pipeline import diagnose

__all__ = ["diagnose", "recording_io"]
