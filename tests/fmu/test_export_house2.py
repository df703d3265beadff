"""`twin export-fmu house2`: a house without a CHP exports, validates in fmpy with its own inputs
and units, and steps an hour like the native house (as tests/fmu/test_export.py for house 1)."""
import importlib.util

import numpy as np
import pytest

from cli.main import main
from plant.house import load_house
from tests.conftest import require_tool

DT = 60.0
#: heat pump on at full modulation into the upper port pair, back-up heater off, boiler at 6 V,
#: solar pump off, heating circuit at 35 degC / 0.2 kg/s, district-heating substation idle on a
#: 70/40 degC grid
COMMANDS = {"heat_pump.on": 1.0, "heat_pump.y_set": 1.0, "heat_pump.aux": 0.0, "hp_valve.upper": 1.0,
            "boiler.U_set": 6.0, "solar.on": 0.0, "solar.m_flow_set": 0.0, "mixer.T_sup_set": 35.0,
            "mixer.m_flow_set": 0.2, "substation.m_flow_set": 0.0, "substation.m_flow_grid_set": 0.0,
            "substation.T_grid_sup": 70.0, "substation.T_grid_ret": 40.0}


@pytest.fixture(scope="module")
def house2_fmu(tmp_path_factory):
    require_tool("pythonfmu", 'pip install -e ".[test]"', found=importlib.util.find_spec("pythonfmu") is not None)
    out = tmp_path_factory.mktemp("export") / "house2.fmu"
    assert main(["export-fmu", "house2", "--out", str(out)]) == 0
    return out


def native_run(names, controller):
    house = load_house("house2", controller=controller)
    rows = [[house.get(n) for n in names]]
    for _ in range(int(3600 / DT)):
        if controller == "external":
            for name, value in COMMANDS.items():
                house.set(name, value)
        house.step(DT)
        rows.append([house.get(n) for n in names])
    return np.array(rows)


@pytest.mark.parametrize("controller", ["external", "rule_based"])
def test_house2_fmu_steps_an_hour_like_the_native_house(house2_fmu, controller):
    from fmpy import simulate_fmu
    from fmpy.validation import validate_fmu

    from plant.fmu.inspect import inspect_fmu

    catalogue = load_house("house2").catalogue
    outputs = [s.name for s in catalogue if s.causality == "output"]
    if controller == "external":
        assert validate_fmu(str(house2_fmu)) == []
        by = {v.name: v for v in inspect_fmu(house2_fmu).variables}
        assert [n for n, v in by.items() if v.causality == "input"] == list(COMMANDS)
        assert all(by[s.name].unit == s.unit for s in catalogue), "units as in the catalogue"
        start = COMMANDS  # constant inputs: no interpolation between communication points
    else:
        start = {"use_builtin_controller": True}
    res = simulate_fmu(str(house2_fmu), start_time=0.0, stop_time=3600.0, output_interval=DT,
                       start_values=start, output=outputs)
    fmu = np.array([res[n] for n in outputs]).T
    native = native_run(outputs, controller)
    diff = np.abs(fmu - native).max(axis=0)
    assert diff.max() < 1e-9, {n: d for n, d in zip(outputs, diff) if d >= 1e-9}  # the same kernel
    ran = native[:, outputs.index("heat_pump.Q_flow")].max()
    assert controller == "rule_based" or ran > 5000.0  # the commands reached the heat pump
