"""The suite's CPU priorities (tests/conftest.py): a real-time test runs at the run's own scheduling
policy, and so does every process it starts; an ordinary test, and what it starts, at the lowest."""
import os
import subprocess
import sys

import pytest

POLICY = "import os; print(os.sched_getscheduler(0) if hasattr(os, 'sched_getscheduler') else os.nice(0))"


def _child_policy() -> int:
    return int(subprocess.run([sys.executable, "-c", POLICY], capture_output=True, text=True, check=True).stdout)


def _lowest() -> int:
    return os.SCHED_IDLE if hasattr(os, "sched_getscheduler") else 19


@pytest.mark.realtime
def test_a_real_time_test_and_its_processes_keep_the_runs_priority():
    assert _child_policy() != _lowest()


def test_an_ordinary_test_and_its_processes_run_at_the_lowest_priority():
    assert _child_policy() == _lowest()
