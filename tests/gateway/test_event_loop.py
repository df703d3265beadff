"""The servers' event-loop choice (twin serve --loop): asyncio's, or uvloop's when installed."""
from __future__ import annotations

import asyncio
import importlib.util

import pytest

from gateway.event_loop import install
from plant.errors import ConfigError

HAVE_UVLOOP = importlib.util.find_spec("uvloop") is not None


@pytest.fixture(autouse=True)
def restore_policy():
    yield
    asyncio.set_event_loop_policy(None)


def test_asyncio_is_asyncio():
    assert install("asyncio") == "asyncio"
    loop = asyncio.new_event_loop()
    assert type(loop).__module__.startswith("asyncio")
    loop.close()


def test_auto_takes_uvloop_when_installed():
    assert install("auto") == ("uvloop" if HAVE_UVLOOP else "asyncio")
    loop = asyncio.new_event_loop()
    assert type(loop).__module__.startswith("uvloop" if HAVE_UVLOOP else "asyncio")
    loop.close()


def test_uvloop_asked_for_but_missing_says_how_to_install(monkeypatch):
    if HAVE_UVLOOP:
        monkeypatch.setitem(__import__("sys").modules, "uvloop", None)  # import uvloop -> ImportError
    with pytest.raises(ConfigError, match=r"\.\[fast\]"):
        install("uvloop")


def test_unknown_choice_names_the_choices():
    with pytest.raises(ConfigError, match="auto, asyncio, uvloop"):
        install("trio")
