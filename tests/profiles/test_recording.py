"""The one recording writer and reader: round trip, rows readable while the run goes on, user CSVs."""
import gzip
import time

import numpy as np
import pytest

from plant.errors import ConfigError, DataError
from profiles.columns import write_columns
from profiles.recording import Recorder, read_recording, write_csv

NAMES = ["storage.T_top", "chp.P_el", "chp.on"]


def _rows(n):
    t = np.arange(n, dtype=float)
    return t, np.column_stack([60.0 + 0.125 * t, 1000.0 * (t % 3), (t % 2)])


def test_round_trip_gives_the_values_and_events_written(tmp_path):
    rec = Recorder(tmp_path / "run", NAMES, {"house": "house1", "start": "2021-01-12"})
    t, rows = _rows(20)
    for ti, row in zip(t, rows):
        rec.signals(ti, row)
    rec.event({"t": 3.0, "kind": "write", "device": "boiler_wolf_cgb", "point": "demand", "value": 1000,
               "accepted": True, "client": "127.0.0.1", "extra": 5})
    rec.event({"t": 4.0, "kind": "request"})  # polling is not logged
    rec.close({"audit": {"clients": {}}})
    back = read_recording(tmp_path / "run")
    assert back.names == NAMES and back.start == "2021-01-12" and back.dropped_rows == 0
    np.testing.assert_array_equal(back.time, t)
    np.testing.assert_array_equal(back.values, rows)  # these values print exactly in %.6g
    np.testing.assert_array_equal(back.signal("chp.P_el"), rows[:, 1])
    assert back.signals == {n: n for n in NAMES} and back.meta["audit"] == {"clients": {}}
    assert [(e["kind"], e["value"], e["accepted"], e["detail"]) for e in back.events] == \
        [("write", "1000", "True", '{"extra": 5}')]


def test_flushed_rows_are_readable_while_the_writer_is_open(tmp_path):
    rec = Recorder(tmp_path / "run", NAMES, {"start": "2021-01-10"})
    t, rows = _rows(5)
    for ti, row in zip(t, rows):
        rec.signals(ti, row)
    time.sleep(1.2)  # the flush timer runs every 0.5 s; the writer stays open
    back = read_recording(tmp_path / "run")
    np.testing.assert_array_equal(back.values, rows)
    rec.signals(5.0, rows[0])
    rec.close()
    assert len(read_recording(tmp_path / "run").time) == 6


def test_half_written_last_row_is_dropped_and_counted(tmp_path):
    rec = Recorder(tmp_path / "run", NAMES, {})
    for ti, row in zip(*_rows(3)):
        rec.signals(ti, row)
    rec.close()
    with open(tmp_path / "run" / "signals.csv", "a") as fh:
        fh.write("3.000,60.5")
    back = read_recording(tmp_path / "run")
    assert len(back.time) == 3 and back.dropped_rows == 1


def test_user_csv_through_a_columns_file(tmp_path):
    t = np.array([0.0, 60.0, 120.0])
    f = write_csv(tmp_path / "lab.csv", t, {"TS_top": np.array([60.0, 61.0, np.nan]),
                                            "FLOW": np.array([12.0, 12.5, 13.0])})
    write_columns(tmp_path / "columns.toml", {"TS_top": "storage.T_top", "FLOW": "mixer.m_flow"},
                  {"TS_top": "degC", "FLOW": "l/min"}, start="2021-01-11", file=f.name)
    for back in (read_recording(f, tmp_path / "columns.toml"), read_recording(tmp_path)):
        assert back.start == "2021-01-11" and back.names == ["TS_top", "FLOW"]
        assert back.signals["FLOW"] == "mixer.m_flow" and back.units["FLOW"] == "l/min"
        np.testing.assert_array_equal(back.time, t)
        np.testing.assert_array_equal(back.signal("mixer.m_flow"), [12.0, 12.5, 13.0])
        assert np.isnan(back.column("TS_top")[2])
    # without a columns file each column is named after its signal
    assert read_recording(f).signals == {"TS_top": "TS_top", "FLOW": "FLOW"}


def test_gzipped_csv_and_cells_that_are_not_numbers(tmp_path):
    f = tmp_path / "lab.csv.gz"
    with gzip.open(f, "wt") as fh:
        fh.write("time,a\n0,1\n1,NA\n2,\n\n3,x\n")
    back = read_recording(f)
    np.testing.assert_array_equal(back.time, [0, 1, 2, 3])
    assert back.values[0, 0] == 1.0 and np.isnan(back.values[1:, 0]).all()
    big = write_csv(tmp_path / "big.csv", np.arange(100.0), {"a": np.ones(100)}, gzip_above=10)
    assert big.name == "big.csv.gz" and len(read_recording(big).time) == 100


def test_errors_name_the_file_and_what_to_give(tmp_path):
    with pytest.raises(ConfigError, match="no such recording"):
        read_recording(tmp_path / "missing.csv")
    (tmp_path / "empty").mkdir()
    with pytest.raises(ConfigError, match=r"signals.csv missing"):
        read_recording(tmp_path / "empty")
    bad = tmp_path / "x.csv"
    bad.write_text("a,b\n1,2\n")
    with pytest.raises(DataError, match="needs a 'time' column"):
        read_recording(bad)
    cols = tmp_path / "c.toml"
    cols.write_text("[units]\n")
    with pytest.raises(ConfigError, match=r"needs a \[columns\] table"):
        read_recording(bad, cols)


def test_a_time_column_of_iso_date_times_under_its_own_name(tmp_path):
    """A DAQ export with stamps instead of seconds: `[recording] time` names the column; the
    stamps become seconds since [recording] start, or since the earliest stamp (then the start);
    stamps with a UTC offset keep their own offset; an unreadable stamp is NaN (dropped later)."""
    (tmp_path / "lab.csv").write_text("Timestamp,TS_top\n2021-01-11 00:01:00,60\n2021-01-11T00:02:30,61\n"
                                      "garbage,62\n2021-01-11 00:03:00,63\n")
    cols = tmp_path / "columns.toml"
    cols.write_text('[recording]\nstart = "2021-01-11"\ntime = "Timestamp"\n[columns]\n"TS_top" = "storage.T_top"\n')
    back = read_recording(tmp_path / "lab.csv", cols)
    assert back.names == ["TS_top"] and back.start == "2021-01-11"
    np.testing.assert_array_equal(back.time[[0, 1, 3]], [60.0, 150.0, 180.0])
    assert np.isnan(back.time[2]) and back.values[3, 0] == 63.0
    cols.write_text('[recording]\ntime = "Timestamp"\n[columns]\n"TS_top" = "storage.T_top"\n')
    back = read_recording(tmp_path / "lab.csv", cols)
    assert back.start == "2021-01-11T00:01:00"
    np.testing.assert_array_equal(back.time[[0, 1, 3]], [0.0, 90.0, 120.0])
    # a logger that switched its offset: each stamp counts in its own; the start in the earliest's
    (tmp_path / "utc.csv").write_text("Timestamp,TS_top\n2021-01-11T00:01:00+01:00,60\n2021-01-11T00:02:00+00:00,61\n")
    cols.write_text('[recording]\nstart = "2021-01-11"\ntime = "Timestamp"\n[columns]\n"TS_top" = "storage.T_top"\n')
    np.testing.assert_array_equal(read_recording(tmp_path / "utc.csv", cols).time, [60.0, 3720.0])


def test_a_missing_or_unreadable_time_column_is_named(tmp_path):
    (tmp_path / "lab.csv").write_text("Zeitstempel,TS_top\n2021-01-11 00:01:00,60\n")
    with pytest.raises(DataError, match=r"needs a 'time' column .*\[recording\] time = .*Columns are: Zeitstempel"):
        read_recording(tmp_path / "lab.csv")
    cols = tmp_path / "columns.toml"
    cols.write_text('[recording]\ntime = "Zeitstempl"\n[columns]\n"TS_top" = "storage.T_top"\n')
    with pytest.raises(DataError, match="needs a 'Zeitstempl' column .*did you mean Zeitstempel"):
        read_recording(tmp_path / "lab.csv", cols)
    (tmp_path / "words.csv").write_text("time,TS_top\nmonday,60\ntuesday,61\n")
    with pytest.raises(DataError, match="neither seconds nor ISO date-times .*first cell 'monday'"):
        read_recording(tmp_path / "words.csv")
    (tmp_path / "mixed.csv").write_text("time,TS_top\n2021-01-11T00:01:00,60\n2021-01-11T00:02:00+01:00,61\n")
    with pytest.raises(DataError, match="with and without a UTC offset"):
        read_recording(tmp_path / "mixed.csv")
