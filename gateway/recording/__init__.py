"""Run recordings: one directory per run with signals.csv, events.csv and meta.json."""
from .reader import Recording, read_recording
from .writer import Recorder

__all__ = ["Recorder", "Recording", "read_recording"]
