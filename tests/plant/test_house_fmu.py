"""House 1 with its heating storage as the C storage FMU (plant/fmu/build.py): the `storage_fmu`
kind, called from the compiled step."""
from pathlib import Path

import numpy as np
import pytest

from plant.catalogue import CATALOGUE
from plant.errors import ConfigError
from plant.house import load_house
from tests.conftest import require_tool

HOUSE1 = Path(__file__).resolve().parents[2] / "plant" / "houses" / "house1.toml"
STORAGE_T = [CATALOGUE.index(f"storage.T_sensor_{i}") for i in range(1, 11)] + [
    CATALOGUE.index("storage.T_top"), CATALOGUE.index("storage.T_bot")]

BINDINGS = '''
[storage.bindings]
m_flow = { var = "m_flow", unit = "kg/s" }
T_in_top = { var = "T_in_top", unit = "K" }
T_in_bottom = "T_in_bottom"
T_out = "T_out"
Q_loss = { var = "Q_loss", unit = "W" }
T_layer = "T_layer[{i}]"
T_sensor_10 = "T_sensor[10]"

[storage.parameters]
volume = { value = 0.8, unit = "m3" }
height = 1.63
n_layers = 40
UA_loss = 20.0
T_env = { value = 18.0, unit = "degC" }
T_init_top = { value = 70.0, unit = "degC" }
T_init_bottom = { value = 45.0, unit = "degC" }
'''


def fmu_house_file(tmp_path, fmu, bindings=BINDINGS, fmu_line=None):
    text = HOUSE1.read_text().replace('kind = "storage"\n', 'kind = "storage_fmu"\n', 1)
    anchor = "soc_Tmax = 80.0\n"
    assert anchor in text
    line = fmu_line if fmu_line is not None else f'fmu = "{fmu}"\n'
    path = tmp_path / "house1_fmu.toml"
    path.write_text(text.replace(anchor, anchor + line + bindings, 1))
    return path


@pytest.fixture(scope="module")
def storage_fmu(tmp_path_factory):
    require_tool("gcc", "apt-get install gcc")  # the storage FMU is compiled from C source
    from plant.fmu.build import build_storage_fmu

    return build_storage_fmu(cache_dir=tmp_path_factory.getbasetemp() / "fmu-cache")


def test_house_with_fmu_storage_closes_its_balance_and_matches_native(storage_fmu, tmp_path):
    house = load_house(fmu_house_file(tmp_path, storage_fmu))
    native = load_house("house1")
    try:
        _, rows = house.run(86400, dt=5.0, out_interval=600.0)
        _, rows_n = native.run(86400, dt=5.0, out_interval=600.0)
        L, Ln = house.ledger(), native.ledger()
        with pytest.raises(ConfigError, match="snapshot"):
            house.snapshot()
    finally:
        house.close()
    dT = np.abs(rows[:, STORAGE_T] - rows_n[:, STORAGE_T]).max()
    print(f"FMU storage house, 1 day at 5 s: closure {L['closure']:.2e} of fuel "
          f"({L['fuel'] / 3.6e6:.2f} kWh), storage temperatures vs native max {dT:.2e} K, "
          f"storage loss {L['loss_storage'] / 3.6e6:.4f} vs {Ln['loss_storage'] / 3.6e6:.4f} kWh")
    assert L["fuel"] > 1e8 and L["loss_storage"] > 1e6  # the day really runs generators and the tank
    assert L["closure"] < 1e-3  # the 0.1 % of fuel; measured ~1e-14
    assert dT < 1e-6  # measured ~2e-12 K: the C kernel is the native one
    assert L["fuel"] == pytest.approx(Ln["fuel"], rel=1e-9)


def test_reset_restarts_the_fmu(storage_fmu, tmp_path):
    house = load_house(fmu_house_file(tmp_path, storage_fmu), controller="external")
    try:
        T0 = house.get("storage.T_sensor_10")
        house.set("mixer.m_flow_set", 0.25)
        house.step(3600.0)
        assert house.get("storage.T_sensor_10") != T0
        house.reset()
        assert house.get("storage.T_sensor_10") == pytest.approx(T0, abs=1e-12)
        assert house.ledger()["fuel"] == 0.0
    finally:
        house.close()


@pytest.mark.parametrize("bindings, fmu_line, needles", [
    (BINDINGS.replace('T_out = "T_out"\n', ""), None, ["[storage.bindings]: missing role(s) T_out"]),
    (BINDINGS.replace("Q_loss = {", "Q_los = {"), None, ["[storage.bindings] Q_los: unknown role", "Q_loss"]),
    (BINDINGS.replace('unit = "K" }', 'unit = "W" }'), None,
     ["[storage.bindings] T_in_top: unit mismatch", "'W' (power)", "'degC' (temperature)"]),
    (BINDINGS.replace('"T_layer[{i}]"', '"T_layer[1]"'), None, ["T_layer = 'T_layer[1]': must contain {i}"]),
    (BINDINGS, 'fmu = "nowhere.fmu"\n', ["[storage] fmu = 'nowhere.fmu': no such file"]),
    (BINDINGS.replace("height = 1.63", "height = true"), None, ["[storage.parameters] height"]),
])
def test_bad_storage_fmu_sections_name_file_line_key(storage_fmu, tmp_path, bindings, fmu_line, needles):
    path = fmu_house_file(tmp_path, storage_fmu, bindings, fmu_line)
    with pytest.raises(ConfigError) as exc:
        load_house(path)
    msg = str(exc.value)
    assert f"{path}:" in msg and f"{path}:0 " not in msg, msg
    for needle in needles:
        assert needle in msg, msg


def test_unit_disagreeing_with_the_fmu_is_an_fmu_error(storage_fmu, tmp_path):
    from plant.errors import FmuError

    path = fmu_house_file(tmp_path, storage_fmu, BINDINGS.replace('T_out = "T_out"', 'T_out = { var = "T_out", unit = "degF" }'))
    with pytest.raises(FmuError, match=r"'T_out'.*binding says 'degF' but the FMU declares 'K'"):
        load_house(path)


def test_ports_must_be_the_top_and_bottom_layers(storage_fmu, tmp_path):
    path = fmu_house_file(tmp_path, storage_fmu)
    path.write_text(path.read_text().replace("storage_top = 1.60", "storage_top = 1.20"))
    with pytest.raises(ConfigError, match=r"storage_top: the storage FMU has ports only in its top"):
        load_house(path)


def test_drive_with_an_fmu_storage_matches_the_compiled_drive(storage_fmu, tmp_path):
    """House.drive (the diagnosis' replay) steps an FMU storage from Python on the same schedule
    as the compiled path of a native house: spans cut at whole minutes, midpoint switching."""
    names = ["chp.on", "chp.y_set", "boiler.U_set", "dhw_pump.on", "mixer.T_sup_set", "mixer.m_flow_set"]
    times = np.arange(1, 6 * 60 + 1) * 60.0 + 1.0  # samples 1 s after each minute
    cmd = np.zeros((len(times), len(names)))
    cmd[:, 0] = (times > 3600) & (times < 4 * 3600)
    cmd[:, 1] = 1.0
    cmd[:, 2] = np.where((times > 7200) & (times < 9000), 10.0, 0.0)
    cmd[:, 4], cmd[:, 5] = 60.0, 0.15
    house = load_house(fmu_house_file(tmp_path, storage_fmu), controller="external")
    native = load_house("house1", controller="external")
    try:
        rows = house.drive(times, names, cmd)
    finally:
        house.close()
    rows_n = native.drive(times, names, cmd)
    assert native.t == times[-1]
    assert np.abs(rows[:, STORAGE_T] - rows_n[:, STORAGE_T]).max() < 1e-6
    assert rows_n[:, CATALOGUE.index("chp.mode")].max() > 0  # the CHP really ran
