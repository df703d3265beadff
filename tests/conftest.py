"""Shared fixtures: the shipped house, assembled once per test session where it is only read.

Also `require_tool`, the one way a test says it needs a tool from outside Python's packages.
"""
import os
import shutil

import pytest

from plant.house import load_house


def require_tool(name: str, package: str, found: bool | None = None) -> None:
    """Skip the calling test if tool `name` is missing, naming the `package` that installs it.

    `found` overrides the check (default: `name` is an executable on PATH). Under CI (environment
    variable CI set, e.g. CI=true) a missing tool fails instead: the README's setup command
    installs every tool, so a skip there would hide a test that never ran.
    """
    if found is None:
        found = shutil.which(name) is not None
    if found:
        return
    reason = f"{name} is not installed (install: {package})"
    if os.environ.get("CI", "").strip().lower() not in ("", "0", "false", "no"):
        pytest.fail(f"{reason}; CI is set, where the README's setup command installs it", pytrace=False)
    pytest.skip(reason)


@pytest.fixture
def house1():
    return load_house("house1")
