"""rigsim: a clean-room simulator of house 1's lab rig (see rigsim/README.md)."""
__all__ = ["suite", "model", "daq", "core", "inputs", "tables"]
