"""Shared fixtures: the shipped house, assembled once per test session where it is only read.

Also `require_tool`, the one way a test says it needs a tool from outside Python's packages, and
the order and grouping of the tests for the two pytest-xdist workers (`-n 2` in pyproject's
addopts, `--dist loadgroup`): the slowest files are handed out first so that both workers finish
together, and the tests that start HELICS districts run on one worker, one after the other.
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


# Files holding the slowest tests, slowest first (per-test durations of a fresh-clone run, #27).
# Their tests are handed out before all others, each file's in its own order; a file missing here
# only starts later. Keep the list to what a run's --durations shows on top.
SLOW_FIRST = (
    "tests/diagnose/test_independent.py",
    "tests/diagnose/test_cases.py",
    "tests/district/test_federation.py",  # with the rest of its group (SAME_WORKER)
    "tests/diagnose/test_report_plots.py",
    "tests/phil/test_loop.py",
    "tests/phil/test_served.py",
    "tests/e2e/test_python_plc_house2.py",
    "tests/e2e/test_canopen_master.py",
    "tests/e2e/test_python_plc.py",
    "tests/rigsim/test_effects.py",
    "tests/phil/test_compare.py",
)

# Files whose tests run on one worker, one after the other. Each file of "helics" starts HELICS
# districts (a broker and its federates on loopback, some of them paced in real time), so two
# districts never share the machine's ports or its time at once; "phil" likewise for the PHIL
# closed loops.
SAME_WORKER = {
    "tests/district/test_federation.py": "helics",
    "tests/district/test_canopen_district.py": "helics",
    "tests/district/test_two_hosts.py": "helics",
    "tests/e2e/test_c_libmodbus_district.py": "helics",
    # the PHIL closed loops pace a twin and its bench processes against the clock: one at a time
    "tests/phil/test_loop.py": "phil",
    "tests/phil/test_served.py": "phil",
    "tests/phil/test_brine.py": "phil",
    "tests/phil/test_variants.py": "phil",
    "tests/phil/test_grid.py": "phil",
    "tests/phil/test_canopen_link.py": "phil",
    "tests/phil/test_compare.py": "phil",
}


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """The files of SLOW_FIRST first, in its order, then the rest as collected (a stable sort)."""
    rank = {path: i for i, path in enumerate(SLOW_FIRST)}
    items.sort(key=lambda item: rank.get(item.nodeid.split("::", 1)[0], len(rank)))


def pytest_xdist_make_scheduler(config, log):
    """--dist loadgroup with the groups of SAME_WORKER, named by file: pytest-xdist 3.8 marks a
    test's xdist_group by rewriting its node id, which pytest 9.2 ignores (pytest-xdist#1386), so
    the marks would be dropped without a word."""
    if config.getoption("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    class FileGroups(LoadGroupScheduling):
        def _split_scope(self, nodeid: str) -> str:
            return SAME_WORKER.get(nodeid.split("::", 1)[0]) or super()._split_scope(nodeid)

    return FileGroups(config, log)


_warmup = None  # tests/plant_warmup.py's pool while it compiles, in the controller of a run


def pytest_sessionstart(session):
    """A whole-suite run on workers (`python3 -m pytest`, no paths given) first compiles every
    shipped house once, one process per worker, while the workers collect the tests."""
    global _warmup
    config = session.config
    whole_suite = config.args_source == pytest.Config.ArgsSource.TESTPATHS
    workers = config.getoption("numprocesses", None) or 0
    if whole_suite and isinstance(workers, int) and workers > 1 and not os.environ.get("PYTEST_XDIST_WORKER"):
        from tests.plant_warmup import Warmup

        _warmup = Warmup(jobs=workers)


def pytest_xdist_node_collection_finished(node, ids):
    """The tests are handed out once the warm-up has compiled every shipped house."""
    global _warmup
    if _warmup is not None:
        line, _warmup = _warmup.wait(), None
        reporter = node.config.pluginmanager.get_plugin("terminalreporter")
        if reporter is not None:
            reporter.write_line(line)


def pytest_sessionfinish(session):
    if _warmup is not None:  # the workers never finished collecting
        _warmup.pool.shutdown(cancel_futures=True)


@pytest.fixture
def house1():
    return load_house("house1")
