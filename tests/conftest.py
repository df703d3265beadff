"""Shared fixtures: the shipped house, assembled once per test session where it is only read."""
import pytest

from plant.house import load_house


@pytest.fixture
def house1():
    return load_house("house1")
