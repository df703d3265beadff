"""A bench fault injected while a PHIL loop runs, and what every bad-bench test checks after it:
the measurement rejected with its interface named, the run stopped, the recording intact and
flagged to its last row."""
from __future__ import annotations

import csv
import threading
import time
from pathlib import Path


def events(run: Path) -> list[dict]:
    return list(csv.DictReader((run / "events.csv").open()))


def rows(run: Path) -> tuple[list[str], list[list[str]]]:
    data = list(csv.reader((run / "signals.csv").open()))
    return data[0], data[1:]


# wall seconds into a run at which a fault is injected: the loops of these tests warm up 20
# simulated s at 100x (0.2 s of wall time), so the fault comes after ~20 counted steps with good
# measurements (a good value to hold, a rejection the report counts); what follows the fault
# (stale_s, stop_s) is timed from the fault, not from the start. stop_s needs only to follow
# stale_s by enough steps (0.3 s: 15 steps at 100x) for the stale rejections to be recorded
# before the stop
FAULT_AFTER_S = 0.6


def run_with_fault(server, loop, action: str, point: str, after: float = FAULT_AFTER_S) -> tuple[dict, dict]:
    """Run `loop` against the in-process bench `server`; `after` s into it: "open" (the sensor
    `point` broken: NaN from a float register, the top of a scaled one), "drift" (reading 100 K
    high), "stop" (the PLC's server gone: connection refused) or "fail" (the PLC answering
    exception 04 past the loop's stop_s, then recovering). -> (report, the bench's inputs at the
    end)."""
    def inject():
        time.sleep(after)
        if action == "open":
            server.device.inject_sensor_fault(point, "open")
        elif action == "drift":
            server.device.inject_sensor_fault(point, "drift", 100.0)
        elif action == "stop":
            server.transport.stop()
        else:
            server.fail()
            time.sleep(1.6)
            server.fail(False)
    try:
        threading.Thread(target=inject, daemon=True).start()
        report = loop.run()
        time.sleep(0.1)
        return report, dict(server.model.inputs)
    finally:
        server.stop()


def assert_rejected_and_stopped(run: Path, bench: str, point: str, reason: str) -> list[dict]:
    """The bad value rejected (with `reason`) on `point` of `bench` only, the run's last event
    its stop, and the recording intact with `point` flagged in its last row. -> the events."""
    ev = events(run)
    rejected = [e for e in ev if e["kind"] == "rejected"]
    assert rejected and all(e["device"] == bench for e in rejected)
    assert any(reason in e["reason"] and e["point"] == point for e in rejected)
    assert ev[-1]["kind"] == "stop"
    head, data = rows(run)
    flag = head.index(f"{bench}.{point}.flag")
    assert data[-1][flag] == "1" and len(data[-1]) == len(head)
    return ev
