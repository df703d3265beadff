"""plant/components/generator.py: the Mode codes, the constants the kernels use, and the mode
signal's description made from them (issue #27, one generator base)."""
import re
import tomllib
from pathlib import Path

import pytest

from plant import kinds
from plant.components import generator
from plant.components.generator import Mode, describe

ROOT = Path(__file__).resolve().parents[2]


def test_the_kernels_constants_are_the_codes():
    assert [int(m) for m in Mode] == list(range(9))
    for m in Mode:
        assert getattr(generator, m.name) == float(m) and isinstance(getattr(generator, m.name), float)
    assert describe((Mode.IDLE, Mode.RUN_ON), {Mode.RUN_ON: "cool-down"}) == "0 idle, 4 cool-down"


@pytest.mark.parametrize("kind", ["boiler", "chp", "heat_pump_air", "heat_pump_brine"])
def test_every_generator_kind_derives_from_the_base(kind):
    k = kinds.KINDS[kind]
    assert isinstance(k, generator.Generator) and k.role == "generator" and k.MODES


@pytest.mark.parametrize("device", ["chp_neotower2", "chp_neotower5", "heat_pump_wolf_cha10",
                                    "heat_pump_wolf_bws1_10"])
def test_a_device_names_the_codes_as_the_kind_describes_them(device):
    """The served operating-state register and the catalogue's description agree code by code."""
    text = (ROOT / "devices" / f"{device}.toml").read_text()
    point = re.search(r'signal = "\w+\.mode", enum = \{([^}]*)\}', text)
    enum = {int(k): v for k, v in tomllib.loads(f"e = {{{point.group(1)}}}")["e"].items()}
    kind = kinds.KINDS["chp" if device.startswith("chp") else "heat_pump_air"]
    words = dict(re.findall(r"(\d+) ([a-z][a-z -]*?)\s*(?:,|$)", describe(kind.MODES, kind.MODE_WORDS)))
    shared = set(enum) & {int(k) for k in words}
    assert shared and all(enum[k] == words[str(k)] for k in shared), (enum, words)
