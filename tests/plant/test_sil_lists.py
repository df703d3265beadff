"""plant/houses/<house>_sil.toml: the SiL signals of reference §13.1 per house map onto signals the
house's catalogue has, in units that convert, and read as a columns file; every §13.1 name is
either mapped or named in a comment with the reason the house lacks it."""
import re
from pathlib import Path

import numpy as np
import pytest

from plant.compiler import catalogue_of
from plant.units import convertible
from profiles.columns import read_columns
from profiles.recording import read_recording

HOUSES = Path(__file__).resolve().parents[2] / "plant" / "houses"
#: the names reference §13.1 gives: SF1's inputs, SF2's and SF3's own inputs, the outputs it
#: names (buffer and DHW-tank layers, zones, model time) and SF2's and SF3's extra outputs
SIL_NAMES = (
    "CHP_CHPon_off", "CHP_elPowerCHP_set", "EB_EBon_off", "EB_EB_power_kW_set", "ST_S_FW_ST_VL_set",
    "TS_S_FW_HC_HW_set", "CHN_S_FW_HC_set", "CHN_S_FW_TG_set", "CHN_S_TM_TG",
    "ASHP_ASHP_mode", "ASHP_Modulation_set", "ASHP_A_V3_TL", "GSHP_GSHP_on", "GSHP_AuxModulation_set",
    "GSHP_A_V3_TL", "ST_A_V3_TL",
    *[f"TS_S_TM_BT_{i}" for i in range(1, 11)], "TS_S_TM_HWS_1", "TS_S_TM_HWS_2", "TS_S_TM_HWS_3",
    "S_TM_ambient", "S_TM_room", "S_TM_roof", "S_TM_cellar", "Modeltime_s",
    "HP_S_TM_VL", "HP_S_TM_RL", "HP_S_TM_HC_TL", "HP_S_TM_HW_TH", "HP_S_FW_HC", "HP_P_heat_HP",
    "HP_P_heat_Aux", "HP_P_heat_Tot", "HP_P_cooling", "HP_P_elec_is", "HP_COP", "HP_EER",
    "PV_P_gen", "PV_E_gen", "RelativHumidityAir_percent",
    "HP_S_TM_BC_VL", "HP_S_TM_BC_RL", "HP_S_FW_BC", "PV_P", "PV_E",
)
#: inputs a controller writes that each house must map (its generators' commands)
COMMANDS = {
    "house1": {"CHP_CHPon_off": "chp.on", "EB_EB_power_kW_set": "boiler.U_set"},
    "house2": {"ASHP_Modulation_set": "heat_pump.y_set", "ASHP_A_V3_TL": "hp_valve.upper",
               "EB_EB_power_kW_set": "boiler.U_set", "ST_S_FW_ST_VL_set": "solar.m_flow_set"},
    "house3": {"GSHP_GSHP_on": "heat_pump.on", "GSHP_A_V3_TL": "hp_branch.upper",
               "ST_S_FW_ST_VL_set": "solar.m_flow_set", "ST_A_V3_TL": "solar.upper"},
    "house4": {"EB_EB_power_kW_set": "boiler.U_set"},
    "house5": {"CHP_CHPon_off": "chp.on", "CHP_elPowerCHP_set": "chp.y_set", "EB_EB_power_kW_set": "boiler.U_set"},
}
#: every house's district-heating substation (§13.1 CHN_*)
for _commands in COMMANDS.values():
    _commands.update({"CHN_S_FW_HC_set": "substation.m_flow_set", "CHN_S_FW_TG_set": "substation.m_flow_grid_set",
                      "CHN_S_TM_TG": "substation.T_grid_sup"})


@pytest.mark.parametrize("house", list(COMMANDS))
def test_sil_list_maps_onto_the_house_catalogue(house, tmp_path):
    path = HOUSES / f"{house}_sil.toml"
    columns = read_columns(path)["columns"]
    catalogue = {s.name: s for s in catalogue_of(house)}
    problems = []
    for name, entry in columns.items():
        entry = {"signal": entry} if isinstance(entry, str) else entry
        signal = catalogue.get(entry["signal"])
        if signal is None:
            problems.append(f"{name}: {entry['signal']} is not a signal of {house}")
        elif "unit" in entry and not convertible(entry["unit"], signal.unit):
            problems.append(f"{name}: {entry['unit']} does not convert to {signal.name} [{signal.unit}]")
    assert not problems, problems
    for name, signal in COMMANDS[house].items():
        assert columns[name] == signal or columns[name]["signal"] == signal, name
        assert catalogue[signal].causality == "input", name
    # every §13.1 name once: a mapping or a '# "NAME": why' comment
    commented = re.findall(r'^# "([A-Za-z0-9_]+)": \S', path.read_text(), flags=re.M)
    named = list(columns) + commented
    assert sorted(named) == sorted(SIL_NAMES), (set(SIL_NAMES) ^ set(named))
    # and the file reads a log in the SiL's names (the entries' keys and ranges checked there)
    log = tmp_path / "log.csv"
    log.write_text(",".join(["time", *columns]) + "\n" + ",".join(["0"] + ["1"] * len(columns)) + "\n")
    rec = read_recording(log, path)
    assert rec.names == list(columns) and np.all(rec.values == 1.0)
    assert set(rec.signals.values()) <= set(catalogue)


@pytest.mark.parametrize("house", list(COMMANDS))
def test_house_doc_names_its_sil_list(house):
    doc = (HOUSES / f"{house}.md").read_text()
    signals = doc[doc.index("## Signals"):doc.index("## Profiles")]
    assert f"{house}_sil.toml" in signals


def test_sil_lists_are_not_houses():
    from plant.errors import ConfigError
    from plant.housefile import resolve, shipped

    assert "house2" in shipped() and not [n for n in shipped() if n.endswith("_sil")]
    with pytest.raises(ConfigError, match="house 'house2_sil': not found; shipped houses: house1"):
        resolve("house2_sil")
