"""A higher-fidelity "truth" of house 1 (pressure-driven hydraulics, finer storage, sensor lag) as
a house-file variant, and the two makers of recordings from the twin with known effects: the
lab-like recording directories (recording.py, `twin make-recording`) and the in-memory samples
the diagnosis's tests and benchmark run on (synth.py). The independent simulators (labsim/,
rigsim/) make their own."""
from .house import TRUTH, load_truth

__all__ = ["TRUTH", "load_truth"]
