"""python-plc example (pymodbus client) against the gateway over Modbus TCP for one winter day."""
from .conftest import DAY, SCAN, check_against_offline, load_example, make_runtime, modbus_port, recorded_kpis


def test_python_plc_one_winter_day_matches_the_built_in_rules(tmp_path, offline_kpis):
    plc_module = load_example("python-plc")
    rt = make_runtime(tmp_path / "run")
    with rt:
        plc = plc_module.CaseStudyPLC("127.0.0.1", modbus_port(rt))
        for _ in range(DAY // SCAN):
            result = plc.scan()
            assert result.ok, result.error
            rt.clock.step(SCAN)
        plc.close(safe=False)   # the run is over; 'safe' would write after the last step anyway
    assert plc.errors == 0
    check_against_offline(recorded_kpis(tmp_path / "run"), offline_kpis)
