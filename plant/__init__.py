"""Simulated CoSES house: components, houses, profiles binding, signal catalogue."""
