"""A higher-fidelity "truth" of house 1 (pressure-driven hydraulics, finer storage, sensor lag) as
a house-file variant, and the generator of lab-like recordings with known, concealed effects."""
from .house import TRUTH, load_truth

__all__ = ["TRUTH", "load_truth"]
