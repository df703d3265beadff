"""A higher-fidelity "truth" of house 1 (pressure-driven hydraulics, finer storage, sensor lag)
and the generator of lab-like recordings with known, concealed effects (see recording.py)."""
from .house import TruthHouse, load_truth

__all__ = ["TruthHouse", "load_truth"]
