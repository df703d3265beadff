"""The pipe diagnosis on real measurements (profiles/recordings/pipes/): ULg 151202 names the wall's
heat capacity near the steel's and cuts the held-out RMSE; bad pipe recordings are refused by name."""
import shutil
from pathlib import Path

import numpy as np
import pytest

from cli.main import main as twin
from plant.diagnose import pipe_recording as pr
from plant.diagnose.pipe_line import diagnose_pipe, format_report, split
from plant.errors import ConfigError

PIPES = Path(__file__).resolve().parents[2] / "profiles" / "recordings" / "pipes"


def test_ulg151202_names_the_wall_capacity_near_the_steels_and_cuts_the_held_out_rmse():
    r = diagnose_pipe(PIPES / "ULg151202")
    first = r["effects"][0]
    assert first["effect"] == "wall_capacity"
    assert 0.7 < first["ratio"] < 1.3                       # fitted C vs the steel wall's mass x cp
    assert r["rmse_diagnosed"] < 0.2 * r["rmse_plain"]      # 5.1 K -> 0.5 K measured
    text = format_report(r)
    assert "EFFECT wall_capacity" in text and "Modelica PlugFlowPipe" in text
    assert r["reference"]["rmse_modelica"] < 1.0


def test_the_split_alternates_blocks_and_skips_nothing_with_a_declared_start():
    rec = pr.load(PIPES / "ULg151202")
    train, held, block = split(rec)
    assert not np.any(train & held) and np.all(train | held)
    assert block == pytest.approx(rec.delay() / 4.0)
    assert 0.4 < train.mean() < 0.6


def _copy(tmp_path) -> Path:
    d = tmp_path / "rec"
    shutil.copytree(PIPES / "ULg151202", d)
    return d


def _drop_line(path: Path, start: str) -> None:
    path.write_text("".join(line for line in path.read_text().splitlines(True) if not line.startswith(start)))


@pytest.mark.parametrize("column, words", [('"m_flow"', ("pipe.m_flow", "mass flow")),
                                           ('"T_in"', ("pipe.T_in", "inlet")),
                                           ('"T_out"', ("pipe.T_out", "outlet"))])
def test_a_recording_without_flow_inlet_or_outlet_is_refused_with_the_file_and_the_fix(tmp_path, column, words):
    d = _copy(tmp_path)
    _drop_line(d / "columns.toml", column)
    with pytest.raises(ConfigError) as e:
        pr.load(d)
    text = str(e.value)
    assert str(d / "columns.toml") in text and all(w in text for w in words) and "signal =" in text


@pytest.mark.parametrize("value", ["0", "nan"])
def test_an_all_zero_or_nan_flow_is_refused(tmp_path, value):
    d = _copy(tmp_path)
    lines = (d / "recording.csv").read_text().splitlines()
    head = lines[0].split(",")
    i = head.index("m_flow")
    rows = [line.split(",") for line in lines[1:]]
    for r in rows:
        r[i] = value
    (d / "recording.csv").write_text("\n".join([lines[0]] + [",".join(r) for r in rows]) + "\n")
    with pytest.raises(ConfigError) as e:
        pr.load(d)
    assert str(d / "recording.csv") in str(e.value) and "all zero or NaN" in str(e.value)


def test_the_command_names_a_missing_pipe_declaration(tmp_path, capsys):
    d = _copy(tmp_path)
    (d / "pipe.toml").unlink()
    assert twin(["diagnose-pipe", "--recording", str(d)]) == 2
    assert "pipe.toml: no pipe declaration" in capsys.readouterr().err
