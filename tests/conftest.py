"""Shared fixtures: the shipped house, assembled once per test session where it is only read.

Also `require_tool`, the one way a test says it needs a tool from outside Python's packages, and
the order and grouping of the tests for the pytest-xdist workers (`-n auto` in pyproject's addopts:
one per core and one more, below; `--dist loadgroup`): the slowest files are handed out first so
that the workers finish together, and the tests that start HELICS districts run on one worker, one
after the other.

Real-time tests (marker `realtime`: a twin, a bench emulator, a district or a runtime paced against
the wall clock, or a latency/period measured on it) are one group, handed out first: one worker runs
them one after the other at the run's CPU priority, while the other workers' tests, like every
ordinary test, run at the lowest (SCHED_IDLE), so a paced process takes a core the moment it wakes
(#27). The real-time worker spends most of its time waiting on the clock, hence the extra worker:
with one worker per core, the cores were not kept busy while the real-time group ran.
"""
import os
import shutil
import tempfile
import warnings
from pathlib import Path

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
    "tests/diagnose/test_report_plots.py",
    "tests/phil/test_loop.py",
    "tests/phil/test_served.py",
    "tests/e2e/test_python_plc_house2.py",
    "tests/e2e/test_canopen_master.py",
    "tests/e2e/test_python_plc.py",
    "tests/rigsim/test_effects.py",
    "tests/phil/test_compare.py",
)

REALTIME = "realtime"  # the marker, and the xdist group of its tests
# Files whose tests run on one worker, one after the other. The files that start HELICS districts
# (a broker and its federates on loopback) hold real-time tests, and are in the real-time group
# whole, so two districts never share the machine's ports at once.
SAME_WORKER = {
    "tests/district/test_federation.py": REALTIME,
    "tests/district/test_canopen_district.py": REALTIME,
    "tests/district/test_two_hosts.py": REALTIME,
    "tests/e2e/test_c_libmodbus_district.py": REALTIME,
}
# Files whose tests share an expensive module- or session-scoped fixture (a diagnosis, a generated
# recording, an FMU or a controller built, a day simulated): on one worker it is computed once per
# run, split over two workers twice. Each file is its own group; the e2e files that compare with
# the session's offline reference day (tests/e2e/conftest.py offline_kpis) are one group.
SHARED_FIXTURE_FILES = (
    "tests/diagnose/test_report_plots.py",     # diagnosed: a labsim diagnosis with plots (~30 s)
    "tests/rigsim/test_effects.py",            # base: the rig simulator's nominal run (~15 s)
    "tests/rigsim/test_physics.py",
    "tests/rigsim/test_suite.py",
    "tests/truth/test_truth_house.py",
    "tests/truth/test_recording.py",
    "tests/plant/test_heat_pump.py",
    "tests/plant/test_solar.py",
    "tests/plant/test_solar_valve.py",
    "tests/plant/test_house_fmu.py",
    "tests/fmu/test_storage_fmu.py",
    "tests/fmu/test_export_house2.py",
    "tests/fmu/test_fmu_errors.py",
    "tests/fmu/test_me_and_fmi3.py",
    "tests/fmu/test_fmu_house.py",
    "tests/fmu/test_export.py",
    "tests/diagnose/test_recording_io.py",
    "tests/rigsim/test_house2.py",             # jan, apr: the house-2 rig's runs (on main since #28)
    # the Modbus contract classes (marked realtime: with the real-time group)
    "tests/gateway/test_modbus_tcp.py",
    "tests/gateway/test_modbus_rtu.py",
)
SAME_WORKER.update({path: path for path in SHARED_FIXTURE_FILES})
SAME_WORKER.update({f"tests/e2e/{name}.py": "e2e-offline-day" for name in
                    ("test_c_libmodbus", "test_canopen_master", "test_offline_reference", "test_python_plc")})
# Tests (node ids) that read the same case of a session-scoped fixture, in a group of their own:
# test_cases.py's truth_reports("storage_heat_loss"), one diagnosis (~30 s) for both
SAME_WORKER_TESTS = {
    "tests/diagnose/test_cases.py::test_storage_heat_loss_is_named_and_sized": "truth-storage_heat_loss",
    "tests/diagnose/test_cases.py::test_nominal_refit_stays_in_bounds_and_does_not_explain_a_concealed_effect":
        "truth-storage_heat_loss",
}


# An ordinary test's process runs at the scheduler's idle policy (SCHED_IDLE; nice 19 where there is
# none): a real-time test's processes (a twin, its bench emulators, a district) keep the run's own
# policy and take a core the moment they wake, while the ordinary tests of the other worker go on
# beside them. SCHED_IDLE, not nice 19: the kernel lets a waking task of the normal policy preempt an
# idle-policy one at once, where nice only weighs the shares.
def _lower_priority() -> None:
    """This process (and what it starts from now on) to the lowest CPU priority; a process
    cannot raise it again."""
    if hasattr(os, "sched_setscheduler"):
        os.sched_setscheduler(0, os.SCHED_IDLE, os.sched_param(0))
    else:
        os.nice(19 - os.nice(0))


def _lowered() -> bool:
    if hasattr(os, "sched_getscheduler"):
        return os.sched_getscheduler(0) == os.SCHED_IDLE
    return os.nice(0) >= 19


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """The real-time tests first, then the files of SLOW_FIRST, in its order, then the rest as
    collected (a stable sort)."""
    rank = {path: i for i, path in enumerate(SLOW_FIRST)}
    items.sort(key=lambda item: (item.get_closest_marker(REALTIME) is None,
                                 rank.get(item.nodeid.split("::", 1)[0], len(rank))))
    # a worker writes the node ids of the real-time tests where the controller's scheduler reads
    # them (the controller collects nothing: it has the node ids, not the marks)
    run_dir = getattr(config, "workerinput", {}).get(_RUN_DIR_KEY)
    if run_dir:
        ids = [item.nodeid for item in items if item.get_closest_marker(REALTIME)]
        path = Path(run_dir) / f"realtime-{config.workerinput['workerid']}.txt"
        path.with_suffix(".tmp").write_text("\n".join(ids))
        path.with_suffix(".tmp").replace(path)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """--dist loadgroup with the groups of SAME_WORKER (by file) and SAME_WORKER_TESTS, and the
    real-time tests, named by their marker, not by xdist_group: pytest-xdist 3.8 marks a test's
    xdist_group by rewriting its node id, which pytest 9.2 ignores (pytest-xdist#1386), so the
    marks would be dropped without a word. The real-time tests are one group, so one worker runs
    them one after the other (two PHIL loops side by side fell behind their clocks on 2 cores:
    CI of 88da169, the SF1 loop's heat error 0.307 % > 0.3 %, the SF3 brine loop's 1.70 % > 0.6 %).
    The groups are handed out in the order of pytest_collection_modifyitems (not xdist's largest
    group first): the real-time group starts the run, then the rest, the slowest first."""
    if config.getoption("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    config.option.loadscopereorder = False

    class FileGroups(LoadGroupScheduling):
        realtime: set[str] = set()  # the node ids of the real-time tests

        def schedule(self) -> None:
            if self.collection is None and _run_dir is not None:  # the first call: read the marks
                for f in sorted(Path(_run_dir).glob("realtime-*.txt")):
                    FileGroups.realtime.update(i for i in f.read_text().splitlines() if i)
            super().schedule()

        def _split_scope(self, nodeid: str) -> str:
            if nodeid in self.realtime:
                return REALTIME
            return (SAME_WORKER_TESTS.get(nodeid) or SAME_WORKER.get(nodeid.split("::", 1)[0])
                    or super()._split_scope(nodeid))

    return FileGroups(config, log)


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_auto_num_workers(config):
    """`-n auto`: a worker per core this process may use, and one for the real-time group, which
    mostly waits on its clocks (cold suite on 2 cores, same commit: 879 s with 2 workers, 835 s
    with 3; the CPU was busy 1.95 cores on average with 3)."""
    return _cores() + 1


def _cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # pragma: no cover - not Linux
        return os.cpu_count() or 1


_RUN_DIR_KEY = "house_twin_run_dir"
_run_dir: str | None = None  # the controller's directory of this run, shared by its workers


def pytest_configure(config):
    global _run_dir
    worker_input = getattr(config, "workerinput", None)
    if worker_input is not None:
        _run_dir = worker_input.get(_RUN_DIR_KEY)
    elif config.pluginmanager.hasplugin("xdist"):
        _run_dir = tempfile.mkdtemp(prefix="house-twin-test-run-")


def pytest_unconfigure(config):
    if getattr(config, "workerinput", None) is None and _run_dir:
        shutil.rmtree(_run_dir, ignore_errors=True)


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node):
    """xdist: each worker gets the controller's run directory."""
    node.workerinput[_RUN_DIR_KEY] = _run_dir


@pytest.hookimpl(tryfirst=True)
def pytest_runtest_setup(item):
    """An ordinary test lowers its process to the lowest priority (once: for good). The real-time
    tests come first (pytest_collection_modifyitems), so a process that runs them is still at the
    run's priority; one that is not gets a warning in the log."""
    if item.get_closest_marker(REALTIME) is None:
        if not _lowered():
            _lower_priority()
    elif _lowered():
        warnings.warn(f"{item.nodeid} runs at the lowest CPU priority, after an ordinary test of this process: "
                      "run the real-time tests first (as the whole suite does)", stacklevel=1)


_warmup = None  # tests/plant_warmup.py's pool while it compiles, in the controller of a run


def pytest_sessionstart(session):
    """A whole-suite run on workers (`python3 -m pytest`, no paths given) first compiles every
    shipped house once, one process per core, while the workers collect the tests (compiling
    keeps a core busy: a process more than cores stretched the warm-up from 114 s to 140 s)."""
    global _warmup
    config = session.config
    whole_suite = config.args_source == pytest.Config.ArgsSource.TESTPATHS
    workers = config.getoption("numprocesses", None) or 0
    if whole_suite and isinstance(workers, int) and workers > 1 and not os.environ.get("PYTEST_XDIST_WORKER"):
        from tests.plant_warmup import Warmup

        _warmup = Warmup(jobs=min(workers, _cores()))


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
