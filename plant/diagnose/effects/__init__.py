"""Catalogue of missing-physics candidates (open interface: see base.py to add your own)."""
from .base import REGISTRY, Effect, Param, UnitEffect, catalogue, register  # noqa: F401
from . import hydraulic, sensor, thermal, units  # noqa: F401  (registers the built-in candidates)
