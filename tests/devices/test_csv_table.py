"""CSV register tables: every shipped map round-trips export -> import, bad tables name line, column and
fix, and a map loaded from CSV answers on Modbus TCP like its TOML original."""
from __future__ import annotations

import csv
import dataclasses
import io
from pathlib import Path

import pytest

from cli.main import main as twin
from gateway.maps import export
from gateway.maps.loader import DEVICES_DIR, load_all, load_map
from gateway.maps.toml_writer import to_toml
from plant.errors import DeviceMapError

MAPS = load_all()


def _same(a, b) -> bool:
    return dataclasses.replace(a, path=b.path) == b


@pytest.mark.parametrize("dev_id", sorted(MAPS))
def test_shipped_map_round_trips_through_csv_and_toml(dev_id: str, tmp_path: Path):
    original = MAPS[dev_id]
    text = export.to_csv(original)
    (tmp_path / f"{dev_id}.csv").write_text(text, encoding="utf-8")
    from_csv = load_map(tmp_path / f"{dev_id}.csv")
    assert _same(from_csv, original)                    # points, addresses, scaling, refs, device block
    assert [p.name for p in from_csv.points] == [p.name for p in original.points]   # PDO order kept
    assert export.to_csv(from_csv) == text
    (tmp_path / "toml").mkdir()
    (tmp_path / "toml" / f"{dev_id}.toml").write_text(to_toml(from_csv), encoding="utf-8")
    assert _same(load_map(tmp_path / "toml" / f"{dev_id}.toml"), original)


def test_spreadsheet_dialect_semicolons_bom_and_padding(tmp_path: Path):
    """What a German-locale spreadsheet saves: ';' separators, a BOM, rows padded with empty cells."""
    rows = list(csv.reader(io.StringIO(export.to_csv(MAPS["dhw_station"]))))
    width = max(len(r) for r in rows)
    buf = io.StringIO()
    csv.writer(buf, delimiter=";", lineterminator="\r\n").writerows(r + [""] * (width - len(r)) for r in rows)
    path = tmp_path / "dhw_station.csv"
    path.write_text("\ufeff" + buf.getvalue(), encoding="utf-8")
    assert _same(load_map(path), MAPS["dhw_station"])


# --- malformed tables -------------------------------------------------------------------------

class Table:
    """dhw_station's exported CSV as rows, to break one cell at a time."""

    def __init__(self) -> None:
        self.rows = list(csv.reader(io.StringIO(export.to_csv(MAPS["dhw_station"]))))
        self.header_at = next(i for i, r in enumerate(self.rows) if r and r[0] == "table")

    def line_of(self, name: str) -> int:
        return next(i for i, r in enumerate(self.rows) if i > self.header_at and r[3] == name) + 1

    def set(self, name: str, column: str, value: str) -> int:
        line = self.line_of(name)
        self.rows[line - 1][self.rows[self.header_at].index(column)] = value
        return line

    def device(self, key: str, *values: str) -> int:
        i = next(i for i, r in enumerate(self.rows) if r and r[0] == key)
        self.rows[i] = [key, *values]
        return i + 1

    def errors(self, tmp_path: Path) -> str:
        path = tmp_path / "dhw_station.csv"
        buf = io.StringIO()
        csv.writer(buf, lineterminator="\n").writerows(self.rows)
        path.write_text(buf.getvalue(), encoding="utf-8")
        with pytest.raises(DeviceMapError) as exc:
            load_map(path)
        return str(exc.value)


def test_cell_that_is_not_a_number_names_line_column_and_fix(tmp_path: Path):
    t = Table()
    line = t.set("t_top", "scale", "abc")
    msg = t.errors(tmp_path)
    assert f'dhw_station.csv:{line} [point t_top] column "scale": "abc" is not a number; write a decimal like 0.1' in msg


def test_unknown_column_names_the_closest(tmp_path: Path):
    t = Table()
    t.rows[t.header_at][t.rows[t.header_at].index("scale")] = "scael"
    msg = t.errors(tmp_path)
    assert f'dhw_station.csv:{t.header_at + 1} register table header column "scael": unknown column' in msg
    assert "closest: scale" in msg and "rename it" in msg


def test_missing_required_column_is_named(tmp_path: Path):
    t = Table()
    col = t.rows[t.header_at].index("ref")
    for r in t.rows[t.header_at:]:
        del r[col:col + 1]
    msg = t.errors(tmp_path)
    assert f"dhw_station.csv:{t.header_at + 1} register table header: missing column(s) ref; add them" in msg


def test_enumerated_values_name_the_closest_valid_value(tmp_path: Path):
    t = Table()
    l_table = t.set("t_top", "table", "inputs")
    l_type = t.set("soc", "type", "int61")
    l_bind = t.set("t_bottom", "binding", "read dhw_storage.T_bottom")
    msg = t.errors(tmp_path)
    assert f"dhw_station.csv:{l_table} [point t_top] table = 'inputs': must be one of " in msg
    assert "(closest: input)" in msg and "(closest: int16)" in msg
    assert f"dhw_station.csv:{l_type} [point soc] type = 'int61'" in msg
    assert (f'dhw_station.csv:{l_bind} [point t_bottom] column "binding": "read dhw_storage.T_bottom" '
            "is not '<how> <what>'; <how> is one of reads, drives, gateway, const (closest: reads)") in msg


def test_duplicated_address_and_name_point_at_both_rows(tmp_path: Path):
    t = Table()
    first = t.line_of("t_top")
    dup = t.set("soc", "address", "0")
    t.set("soc", "printed", "")
    t.set("t_bottom", "name", "t_tap")
    msg = t.errors(tmp_path)
    assert (f'dhw_station.csv:{dup} [point soc] column "address": input address 0 is also used by '
            f"line {first} (t_top); give each point its own address") in msg
    assert (f'dhw_station.csv:{first + 2} [point t_tap] column "name": also on line '
            f'{first + 1}; point names must be unique') in msg


def test_bad_range_address_canopen_and_enum_cells(tmp_path: Path):
    t = Table()
    l_range = t.set("charge_enable", "range", "0-1")
    l_addr = t.set("t_top", "address", "4x0001")
    l_co = t.set("soc", "canopen", "2100/3")
    l_enum = t.set("t_tap", "enum", "zero; 1=on")
    msg = t.errors(tmp_path)
    assert f'dhw_station.csv:{l_range} [point charge_enable] column "range": "0-1" is not low…high; write e.g. 0…100' in msg
    assert f'dhw_station.csv:{l_addr} [point t_top] column "address": "4x0001" is not a whole number; write the 0-based wire address' in msg
    assert f'dhw_station.csv:{l_co} [point soc] column "canopen": "2100/3" is not an object; write index.sub in hex' in msg
    assert f'dhw_station.csv:{l_enum} [point t_tap] column "enum": "zero; 1=on" is not value=label pairs' in msg


def test_device_block_keys_and_values(tmp_path: Path):
    t = Table()
    l_unit = t.device("modbus.unit_id", "300")
    t.rows.insert(l_unit, ["modbus.unitid", "6"])
    l_node = t.device("canopen.node_id", "seventeen")
    msg = t.errors(tmp_path)
    assert f'dhw_station.csv:{l_node} canopen.node_id: "seventeen" is not a number; write a whole number' in msg
    assert f"dhw_station.csv:{l_unit + 1} modbus.unitid: unknown device key; closest: modbus.unit_id" in msg
    assert f"dhw_station.csv:{l_unit} [modbus] unit_id = 300: must be an integer 1…247" in msg


def test_semantic_device_problems_carry_the_line(tmp_path: Path):
    t = Table()
    line = t.device("modbus.unit_id", "300")
    msg = t.errors(tmp_path)
    assert f"dhw_station.csv:{line} [modbus] unit_id = 300: must be an integer 1…247" in msg


def test_edited_printed_number_is_refused_not_ignored(tmp_path: Path):
    t = Table()
    line = t.set("t_top", "printed", "40001")
    msg = t.errors(tmp_path)
    assert (f'dhw_station.csv:{line} [point t_top] column "printed": "40001" but the point gives 0; '
            "change address or type instead, or clear the cell") in msg


def test_all_problems_are_reported_at_once(tmp_path: Path):
    t = Table()
    t.set("t_top", "table", "inputs")
    t.set("charge_enable", "access", "RX")
    t.set("soc", "ref", "")
    msg = t.errors(tmp_path)
    assert "table = 'inputs'" in msg and "access = 'RX'" in msg and "[point soc]: missing key 'ref'" in msg
    assert len(msg.splitlines()) == 3


# --- CLI ----------------------------------------------------------------------------------------

def test_cli_import_table_writes_the_toml(tmp_path: Path, capsys):
    csv_path = tmp_path / "storage_io.csv"
    csv_path.write_text(export.to_csv(MAPS["storage_io"]), encoding="utf-8")
    assert twin(["devices", "lint", str(csv_path), "--no-plant"]) == 0
    assert "0 error(s)" in capsys.readouterr().out
    out = tmp_path / "maps" / "storage_io.toml"
    assert twin(["devices", "import-table", str(csv_path), "--out", str(out)]) == 0
    assert _same(load_map(out), MAPS["storage_io"])
    assert twin(["devices", "import-table", str(csv_path), "--out", str(out)]) == 2   # exists
    assert "--force" in capsys.readouterr().err
    assert twin(["devices", "import-table", str(csv_path), "--out", str(tmp_path / "x.toml")]) == 2
    assert "storage_io.toml" in capsys.readouterr().err
    assert not (DEVICES_DIR / "storage_io.csv").exists()


# --- served ---------------------------------------------------------------------------------------

def test_csv_map_answers_modbus_tcp_like_its_toml_original(tmp_path: Path):
    from pymodbus.client import ModbusTcpClient

    from gateway.device.device import Device
    from gateway.device.plant_port import PlantPort
    from gateway.transports.modbus_tcp import ModbusTcpTransport
    from plant.house import load_house
    from tests.gateway.contract import ClientBus

    dev_id = "boiler_wolf_cgb"
    (tmp_path / f"{dev_id}.csv").write_text(export.to_csv(MAPS[dev_id]), encoding="utf-8")
    port = PlantPort(load_house("house1", controller="external"))
    port.step(60.0)
    answers = []
    for dmap in (load_map(DEVICES_DIR / f"{dev_id}.toml"), load_map(tmp_path / f"{dev_id}.csv")):
        transport = ModbusTcpTransport([Device(dmap, port)], port=0)
        transport.start()
        client = ModbusTcpClient("127.0.0.1", port=transport.port, timeout=0.5, retries=0)
        try:
            assert client.connect()
            bus = ClientBus(client)
            answers.append({p.name: bus.read(dmap.unit_id, p.table, p.address, p.words) for p in dmap.points})
            answers[-1]["write"] = bus.write(dmap.unit_id, "holding", 200, [1001])   # 10.01 V > range
        finally:
            client.close()
            transport.stop()
    toml_answers, csv_answers = answers
    assert all(isinstance(v, list) for k, v in toml_answers.items() if k != "write")
    assert toml_answers["t_boiler"] != [0]
    assert csv_answers == toml_answers
