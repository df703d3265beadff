"""Shared fixtures: the shipped house, assembled once per test session where it is only read.

Also `require_tool`, the one way a test says it needs a tool from outside Python's packages, and
the order and grouping of the tests for the two pytest-xdist workers (`-n 2` in pyproject's
addopts, `--dist loadgroup`): the slowest files are handed out first so that both workers finish
together, and the tests that start HELICS districts run on one worker, one after the other.

Real-time tests (marker `realtime`: a twin, a bench emulator, a district or a runtime paced against
the wall clock, or a latency/period measured on it) never run beside a CPU-bound (ordinary) test:
a lock across the workers (`_CoreLock`) lets ordinary tests run beside each other, real-time tests
one at a time, never beside an ordinary one; the scheduler hands the real-time tests
out first, in one block per worker, so that the machine is drained for them once (#27).
"""
import fcntl
import os
import shutil
import tempfile
import time
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
# districts (a broker and its federates on loopback), so two districts never share the machine's
# ports at once. (The real-time tests are grouped by their marker, in one block per worker; those
# of one group here stay in one block.)
SAME_WORKER = {
    "tests/district/test_federation.py": "helics",
    "tests/district/test_canopen_district.py": "helics",
    "tests/district/test_two_hosts.py": "helics",
    "tests/e2e/test_c_libmodbus_district.py": "helics",
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
    # the Modbus contract classes (marked realtime): their gateway in one real-time block
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
REALTIME = "realtime"  # the marker; its tests' xdist groups are "realtime-0", "realtime-1", ...


@pytest.hookimpl(tryfirst=True)
def pytest_collection_modifyitems(config, items):
    """The real-time tests first (one block, see pytest_xdist_make_scheduler), then the files of
    SLOW_FIRST, in its order, then the rest as collected (a stable sort)."""
    rank = {path: i for i, path in enumerate(SLOW_FIRST)}
    items.sort(key=lambda item: (item.get_closest_marker(REALTIME) is None,
                                 rank.get(item.nodeid.split("::", 1)[0], len(rank))))
    # a worker writes the node ids of the real-time tests where the controller's scheduler reads
    # them (the controller collects nothing: it has the node ids, not the marks)
    lock_dir = getattr(config, "workerinput", {}).get(_LOCK_DIR_KEY)
    if lock_dir:
        ids = [item.nodeid for item in items if item.get_closest_marker(REALTIME)]
        path = Path(lock_dir) / f"realtime-{config.workerinput['workerid']}.txt"
        path.with_suffix(".tmp").write_text("\n".join(ids))
        path.with_suffix(".tmp").replace(path)


# Seconds a real-time test takes (warm plant cache, the real-time tests one at a time on the
# shared 2-core machine, #27: `-m realtime -n 0`, 242 s in all), by node id without parameters
# (a parametrised test: each case's); the others count REALTIME_DEFAULT_S. Only to share the
# real-time tests between the workers' blocks so that they end together.
REALTIME_SECONDS = {
    "tests/phil/test_loop.py::test_sf1_space_heating_dhw_and_solar_agree_with_the_benches": 31.0,
    "tests/phil/test_loop.py::test_bench_below_the_requested_flow_for_two_hours_deficit_reported_and_made_up": 25.5,
    "tests/phil/test_loop.py::test_houses_at_once_step_at_the_phase_each_was_given": 11.5,
    "tests/phil/test_loop.py::test_stale_bench_process_stopped_then_killed": 3.3,
    "tests/phil/test_loop.py::test_bench_reporting_l_per_h_where_the_map_says_l_per_min": 1.7,
    "tests/phil/test_served.py::test_space_heating_bench_as_plc_process_polling_the_twin": 14.5,
    "tests/phil/test_served.py::test_mbpoll_as_the_tap_water_plc_reads_setpoints_and_writes_measurements": 10.0,
    "tests/phil/test_served.py::test_silent_bench_plc_is_named_and_the_safe_setpoints_are_served": 2.3,
    "tests/phil/test_compare.py::test_compare_a_run_with_its_benches_and_the_house_alone": 9.0,
    "tests/phil/test_brine.py::test_sf3_closed_loop_brine_heat_agrees_with_the_ground_collector": 12.5,
    "tests/phil/test_canopen_link.py::test_sf3_closed_loop_over_canopen_brine_heat_agrees_with_the_ground_collector": 21.0,
    "tests/phil/test_canopen_link.py::test_bench_that_stops_sending_tpdos_is_stale_and_gets_the_safe_setpoints": 2.0,
    "tests/phil/test_canopen_link.py::test_two_benches_on_one_bus_one_sync_a_step_and_each_tpdo_once": 4.0,
    "tests/phil/test_grid.py::test_district_house_alone_on_its_grid_against_the_grid_emulator": 12.0,
    "tests/phil/test_grid.py::test_district_house_with_the_other_houses_against_the_grid_emulator": 12.5,
    "tests/phil/test_variants.py::test_twin_phil_runs_the_variant": 4.5,
    "tests/phil/test_variants.py::test_sf2_closed_loop_heat_agrees_with_its_benches": 13.0,
    "tests/district/test_canopen_district.py::test_a_canopen_master_commands_a_substation_of_a_running_district": 11.5,
    "tests/e2e/test_c_libmodbus_district.py::test_c_controller_runs_one_house_of_a_district": 17.5,
}
REALTIME_DEFAULT_S = 2.0


def realtime_blocks(ids: list[str], n: int) -> dict[str, str]:
    """The real-time tests shared into n blocks (groups "realtime-0" ...) of about equal time, the
    longest first to the block with the least; the tests of one SAME_WORKER group (the paced
    districts of "helics") in one block. Each block keeps the tests' order."""
    units: dict[str, list[str]] = {}
    for i in ids:
        units.setdefault(SAME_WORKER.get(i.split("::", 1)[0], i), []).append(i)
    seconds = {u: sum(REALTIME_SECONDS.get(i.split("[", 1)[0], REALTIME_DEFAULT_S) for i in tests)
               for u, tests in units.items()}
    load, out = [0.0] * max(n, 1), {}
    for u in sorted(units, key=lambda u: -seconds[u]):
        k = load.index(min(load))
        load[k] += seconds[u]
        out.update({i: f"{REALTIME}-{k}" for i in units[u]})
    return {i: out[i] for i in ids}


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """--dist loadgroup with the groups of SAME_WORKER (by file) and SAME_WORKER_TESTS, and the
    real-time tests, named by their marker, not by xdist_group: pytest-xdist 3.8 marks a test's
    xdist_group by rewriting its node id, which pytest 9.2 ignores (pytest-xdist#1386), so the
    marks would be dropped without a word. The real-time tests are one block per worker
    (realtime_blocks). The groups and tests are handed out in the order of
    pytest_collection_modifyitems (not xdist's largest group first): the real-time blocks start
    the run, one on each worker, then the rest, the slowest first."""
    if config.getoption("dist") != "loadgroup":
        return None
    from xdist.scheduler import LoadGroupScheduling

    config.option.loadscopereorder = False

    class FileGroups(LoadGroupScheduling):
        realtime: dict[str, str] = {}  # node id -> its real-time group

        def schedule(self) -> None:
            if self.collection is None and _lock_dir is not None:  # the first call: read the marks
                ids: list[str] = []
                for f in sorted(Path(_lock_dir).glob("realtime-*.txt")):
                    ids += [i for i in f.read_text().splitlines() if i and i not in ids]
                FileGroups.realtime = realtime_blocks(ids, len(self.nodes))
            super().schedule()

        def _split_scope(self, nodeid: str) -> str:
            if nodeid in self.realtime:
                return self.realtime[nodeid]
            return (SAME_WORKER_TESTS.get(nodeid) or SAME_WORKER.get(nodeid.split("::", 1)[0])
                    or super()._split_scope(nodeid))

    return FileGroups(config, log)


# --- the lock between ordinary and real-time tests ------------------------------------------------
# flock(2) files in a directory of the run, shared by its workers; per worker w a `rt-w` and a
# `gate-w`. A real-time test on worker w holds rt-w exclusively; an ordinary test holds every other
# worker's rt file shared for its whole protocol (setup, call, teardown). So an ordinary test never
# runs beside a real-time one and ordinary tests run beside each other. Real-time tests run one
# at a time: each worker's block takes `realtime-one` exclusively first (two PHIL loops side by
# side fell behind their clocks on 2 cores). A real-time test takes its gate exclusively before
# rt-w, an ordinary test the gate shared for a moment before rt-w, so that a waiting real-time test
# is not starved by the other worker's stream of ordinary tests. A worker keeps its hold from one
# real-time test to the next (its next item is real-time too), so a block of them drains the
# machine once. Other workers' files are taken in one order (no deadlock). The lock is taken
# outside pytest-timeout's timer (tryfirst: the outermost wrapper): a wait is not a test's time.
# Without xdist the run's one process has no other worker: its locks never wait.
_LOCK_DIR_KEY = "house_twin_lock_dir"
_lock_dir: str | None = None  # this run's directory of the locks (controller, worker or lone run)


class _CoreLock:
    def __init__(self, directory: str, me: str, workers: list[str]):
        def fd(name: str) -> int:
            return os.open(os.path.join(directory, name), os.O_RDWR | os.O_CREAT, 0o600)

        self.my_gate, self.my_rt = fd(f"gate-{me}"), fd(f"rt-{me}")
        # one real-time test at a time across the workers: two PHIL loops side by side (a twin and
        # three bench processes each) fell behind their clocks on 2 cores (CI of 88da169: the SF1
        # loop's heat error 0.307 % > 0.3 %, the SF3 brine loop's 1.70 % > 0.6 %)
        self.one = fd("realtime-one")
        self.others = [(fd(f"gate-{w}"), fd(f"rt-{w}")) for w in sorted(workers) if w != me]
        self.exclusive = False
        self.first = True
        self.waited = 0.0  # seconds this process waited for the lock

    def _take(self, fd: int, how: int) -> None:
        t = time.monotonic()
        fcntl.flock(fd, how)
        self.waited += time.monotonic() - t

    def shared(self) -> None:
        """For an ordinary test: no real-time test runs on another worker until release()."""
        self.release()
        if self.first and self.others and _has_realtime_tests():
            # the run's first test: let the other workers' real-time blocks (handed out first) take
            # their locks before this one, rather than wait for this test to end
            time.sleep(1.0)
        self.first = False
        for gate, rt in self.others:
            self._take(gate, fcntl.LOCK_SH)
            try:
                self._take(rt, fcntl.LOCK_SH)
            finally:
                fcntl.flock(gate, fcntl.LOCK_UN)

    def exclusive_hold(self) -> None:
        """For a real-time test: no ordinary test runs on another worker until release()."""
        self.first = False
        if self.exclusive:
            return
        self.release()
        self._take(self.one, fcntl.LOCK_EX)
        self._take(self.my_gate, fcntl.LOCK_EX)
        self._take(self.my_rt, fcntl.LOCK_EX)
        self.exclusive = True

    def release(self) -> None:
        # LOCK_UN, not close: a child process that inherited a descriptor cannot keep the lock
        for _, rt in self.others:
            fcntl.flock(rt, fcntl.LOCK_UN)
        fcntl.flock(self.my_rt, fcntl.LOCK_UN)
        fcntl.flock(self.my_gate, fcntl.LOCK_UN)
        fcntl.flock(self.one, fcntl.LOCK_UN)
        self.exclusive = False


_core_lock: _CoreLock | None = None


def _has_realtime_tests() -> bool:
    return any(f.stat().st_size for f in Path(_lock_dir).glob("realtime-*.txt"))


def pytest_configure(config):
    global _lock_dir, _core_lock
    worker_input = getattr(config, "workerinput", None)
    if worker_input is not None:
        _lock_dir = worker_input.get(_LOCK_DIR_KEY)
        me, n = worker_input["workerid"], int(worker_input.get("workercount", 1))
        workers = [f"gw{i}" for i in range(n)] if me.startswith("gw") else [me]
    else:
        _lock_dir = tempfile.mkdtemp(prefix="house-twin-test-locks-")
        me, workers = "main", ["main"]
    if _lock_dir:
        _core_lock = _CoreLock(_lock_dir, me, workers)


def pytest_unconfigure(config):
    if getattr(config, "workerinput", None) is None and _lock_dir:
        shutil.rmtree(_lock_dir, ignore_errors=True)


@pytest.hookimpl(optionalhook=True)
def pytest_configure_node(node):
    """xdist: each worker gets the controller's lock directory."""
    node.workerinput[_LOCK_DIR_KEY] = _lock_dir


_lock_stats = {"realtime": 0, "realtime_s": 0.0, "waited_s": 0.0}


def pytest_runtest_logreport(report):
    """(controller or lone run) the lock's figures for the summary"""
    props = dict(report.user_properties)
    if report.when == "teardown" and "core_lock_wait_s" in props:
        _lock_stats["waited_s"] += props["core_lock_wait_s"]
    if report.when in ("setup", "call", "teardown") and props.get("realtime"):
        _lock_stats["realtime"] += report.when == "call"
        _lock_stats["realtime_s"] += report.duration


def pytest_terminal_summary(terminalreporter, config):
    if getattr(config, "workerinput", None) is None and _lock_stats["realtime"]:
        terminalreporter.write_line(
            f"core lock: {_lock_stats['realtime']} real-time tests took {_lock_stats['realtime_s']:.0f} s, no "
            f"other test beside them; tests waited {_lock_stats['waited_s']:.0f} s for the lock in all")


@pytest.hookimpl(hookwrapper=True, tryfirst=True)
def pytest_runtest_protocol(item, nextitem):
    lock = _core_lock
    realtime = item.get_closest_marker(REALTIME) is not None
    if lock is not None:
        waited = lock.waited
        lock.exclusive_hold() if realtime else lock.shared()
        item.user_properties.append(("core_lock_wait_s", round(lock.waited - waited, 3)))
        item.user_properties.append(("realtime", realtime))
    try:
        yield
    finally:
        if lock is not None and not (realtime and nextitem is not None
                                     and nextitem.get_closest_marker(REALTIME) is not None):
            lock.release()


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
