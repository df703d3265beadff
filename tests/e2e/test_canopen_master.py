"""canopen-master example against the gateway's CANopen nodes (virtual bus) for one winter day."""
from profiles.recording import read_recording

from .conftest import DAY, SCAN, check_against_offline, load_example, make_runtime, recorded_kpis


def test_canopen_master_one_winter_day_matches_the_built_in_rules(tmp_path, offline_kpis):
    master_module = load_example("canopen-master")
    bus = f"virtual:e2e_canopen_{tmp_path.name}"
    rt = make_runtime(tmp_path / "run", modbus=False, can=bus)
    with rt:
        master = master_module.CaseStudyMaster(bus)
        master.start()
        try:
            for _ in range(DAY // SCAN):
                master.scan()
                rt.clock.step(SCAN)
        finally:
            master.network.disconnect()
    check_against_offline(recorded_kpis(tmp_path / "run"), offline_kpis)
    writes = [e for e in read_recording(tmp_path / "run").events if e["kind"] == "write"]
    assert writes and all(e["accepted"] == "True" for e in writes)
    assert {e["point"] for e in writes} == {"run_request", "modulation_set", "charge_enable", "demand_voltage"}
