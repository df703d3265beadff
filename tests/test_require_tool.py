"""require_tool: a missing tool skips the test, and fails it under CI, where setup installs it."""
import pytest

from tests.conftest import require_tool


def test_a_present_tool_lets_the_test_run(monkeypatch):
    monkeypatch.setenv("CI", "true")
    require_tool("sh", "apt-get install dash")
    require_tool("libthing", "apt-get install libthing-dev", found=True)


def test_a_missing_tool_skips_naming_its_package(monkeypatch):
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception, match=r"no-such-tool is not installed \(install: apt-get"):
        require_tool("no-such-tool", "apt-get install no-such-tool")
    monkeypatch.setenv("CI", "false")
    with pytest.raises(pytest.skip.Exception):
        require_tool("libthing", "apt-get install libthing-dev", found=False)


def test_a_missing_tool_fails_under_ci(monkeypatch):
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="no-such-tool is not installed.*CI is set"):
        require_tool("no-such-tool", "apt-get install no-such-tool")
