"""rigsim: clean-room simulators of house 1's and (rigsim/house2) house 2's lab rigs (rigsim/README.md)."""
__all__ = ["suite", "model", "daq", "core", "inputs", "tables"]
