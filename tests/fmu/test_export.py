"""`twin export-fmu`: the native twin as an FMI 2.0 CS FMU (pythonfmu) validates in fmpy and
reproduces the native House run driven by the same input schedule."""
import importlib.util

import numpy as np
import pytest

from cli.main import main
from plant.catalogue import CATALOGUE
from plant.house import load_house
from tests.conftest import require_tool

INPUTS = [s.name for s in CATALOGUE.inputs()]
SENSORS = [f"storage.T_sensor_{i}" for i in range(1, 11)]
COMPARED = SENSORS + ["zone.T_room"]
DT = 60.0
HOURS = 6


def needs_pythonfmu():
    require_tool("pythonfmu", 'pip install -e ".[test]"',  # it builds the FMU
                 found=importlib.util.find_spec("pythonfmu") is not None)


@pytest.fixture(scope="module")
def house_fmu(tmp_path_factory):
    needs_pythonfmu()
    out = tmp_path_factory.mktemp("export") / "house1.fmu"
    assert main(["export-fmu", "house1", "--out", str(out)]) == 0  # through the CLI
    return out


def schedule(t):
    """The commands at communication point t: boiler at 10 V for 2 h, CHP on at full load,
    heating circuit at 60 degC / 0.15 kg/s, no DHW charging, the district-heating substation idle
    on a 70/40 degC grid."""
    return {"chp.on": 1.0, "chp.y_set": 1.0, "boiler.U_set": 10.0 if t < 7200.0 else 0.0,
            "dhw_pump.on": 0.0, "mixer.T_sup_set": 60.0, "mixer.m_flow_set": 0.15,
            "substation.m_flow_set": 0.0, "substation.m_flow_grid_set": 0.0,
            "substation.T_grid_sup": 70.0, "substation.T_grid_ret": 40.0}


def native_run(names, seconds, controller="external", start=None, inputs=True):
    house = load_house("house1", start=start, controller=controller)
    rows = [[house.get(n) for n in names]]
    for k in range(int(round(seconds / DT))):
        if inputs:
            for name, value in schedule(k * DT).items():
                house.set(name, value)
        house.step(DT)
        rows.append([house.get(n) for n in names])
    return np.array(rows)


def test_validates_and_declares_the_catalogue(house_fmu):
    from fmpy.validation import validate_fmu

    from plant.fmu.inspect import inspect_fmu

    # no filtering needed: export.py adds the <UnitDefinitions> and <InitialUnknowns> that
    # pythonfmu 0.7.0 leaves out
    assert validate_fmu(str(house_fmu)) == []
    info = inspect_fmu(house_fmu)
    assert info.fmi_version == "2.0" and info.cosimulation and info.platform_problem() is None
    by = {v.name: v for v in info.variables}
    assert [v.name for v in info.variables if v.causality == "input"] == INPUTS
    outputs = [s for s in CATALOGUE if s.causality == "output"]
    assert [v.name for v in info.variables if v.causality == "output"] == [s.name for s in outputs]
    for s in list(CATALOGUE.inputs()) + outputs:
        assert by[s.name].unit == s.unit and by[s.name].type == "Real", s.name
    assert by["mixer.T_sup_set"].unit == "degC" and by["storage.T_sensor_1"].unit == "degC"
    assert by["start_date"].causality == "parameter" and by["start_date"].start == "2021-01-10"
    assert by["use_builtin_controller"].type == "Boolean" and by["use_builtin_controller"].start == "false"


def test_fmpy_simulation_reproduces_the_native_twin(house_fmu):
    from fmpy import simulate_fmu

    # the boiler step at 2 h is a repeated time point: fmpy applies the value after the event
    dtype = [("time", float)] + [(n, float) for n in INPUTS]
    on, off = schedule(0.0), schedule(7200.0)
    table = np.array([(t, *[v[n] for n in INPUTS]) for t, v in
                      ((0.0, on), (7200.0, on), (7200.0, off), (HOURS * 3600.0, off))], dtype=dtype)
    res = simulate_fmu(str(house_fmu), start_time=0.0, stop_time=HOURS * 3600.0, output_interval=DT,
                       input=table, output=COMPARED)
    fmu = np.array([res[n] for n in COMPARED]).T
    native = native_run(COMPARED, HOURS * 3600.0)
    assert np.allclose(res["time"], np.arange(len(native)) * DT)
    diff = np.abs(fmu - native).max(axis=0)
    assert diff.max() < 0.1, dict(zip(COMPARED, diff))
    assert diff.max() < 1e-6, dict(zip(COMPARED, diff))  # the same kernel: round-off only
    # the schedule really moved the plant (not a trivially constant run)
    assert native[:, :10].max() - native[:, :10].min() > 5.0


def test_fmu_component_steps_it_like_the_native_house(house_fmu):
    from plant.fmu.component import FmuComponent

    outputs = {n: (n, "degC") for n in COMPARED}
    outputs["boiler.Q_flow"] = ("boiler.Q_flow", "W")
    with FmuComponent(house_fmu, inputs={n: (n, None) for n in INPUTS}, outputs=outputs) as fmu:
        rows = [fmu.read_outputs()]
        for k in range(120):  # 2 h
            fmu.set_inputs(schedule(k * DT))
            rows.append(fmu.step(DT))
    native = native_run(list(outputs), 7200.0)
    assert np.abs(np.array(rows) - native).max() < 1e-9  # same inputs, no interpolation: exact
    assert native[-1, -1] > 1000.0  # the boiler ran


def test_builtin_controller_flag_and_start_date(house_fmu):
    from fmpy import simulate_fmu

    names = COMPARED + ["weather.T_air", "chp.P_el", "mixer.m_flow"]
    start = "2021-03-01T06:00"  # morning: the thermostat opens the heating circuit, the CHP runs
    res = simulate_fmu(str(house_fmu), start_time=0.0, stop_time=7200.0, output_interval=DT,
                       start_values={"use_builtin_controller": True, "start_date": start},
                       output=names)
    fmu = np.array([res[n] for n in names]).T
    native = native_run(names, 7200.0, controller="rule_based", start=start, inputs=False)
    assert np.abs(fmu - native).max() < 1e-9
    # the built-in controller drove the commands: with the FMU's input start values (chp.on = 0,
    # mixer.m_flow_set = 0) neither would happen
    assert fmu[:, -2].max() > 1000.0 and fmu[:, -1].max() > 0.05
    jan = native_run(["weather.T_air"], 0.0, controller="rule_based")
    assert abs(jan[0, 0] - fmu[0, len(COMPARED)]) > 1e-6  # the start date reached the profiles


def test_errors_are_clear(tmp_path, monkeypatch, capsys):
    assert main(["export-fmu", "house9", "--out", str(tmp_path / "x.fmu")]) == 2
    assert "house 'house9': not found" in capsys.readouterr().err
    assert main(["export-fmu", "house1", "--out", str(tmp_path / "x.fmu"), "--start", "soon"]) == 2
    assert "not a date" in capsys.readouterr().err
    assert main(["export-fmu", "house1", "--out", str(tmp_path / "x.zip")]) == 2
    assert "must end in .fmu" in capsys.readouterr().err
    monkeypatch.setitem(__import__("sys").modules, "pythonfmu", None)  # import pythonfmu -> ImportError
    assert main(["export-fmu", "house1", "--out", str(tmp_path / "x.fmu")]) == 2
    err = capsys.readouterr().err
    assert "pythonfmu" in err and "pip install pythonfmu==0.7.0" in err
    assert not (tmp_path / "x.fmu").exists()
