"""plant/catalogue.py: house 1's catalogue compiles when first read, never when imported."""
import subprocess
import sys

from plant.catalogue import CATALOGUE
from plant.compiler import catalogue_of
from plant.signals import SignalCatalogue

# in a fresh interpreter: the compiler refuses to run, then the modules that hold CATALOGUE import
NO_COMPILE = """
import plant.compiler
def refuse(decl):
    raise SystemExit("a house compiled on import")
plant.compiler.compile_plant = refuse
import plant.catalogue, plant.fmu.house, plant.fmu.housefile, plant.truth.recording, plant.diagnose, cli.main
print("imported")
"""


def test_importing_compiles_no_house():
    p = subprocess.run([sys.executable, "-c", NO_COMPILE], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0 and p.stdout.strip() == "imported", p.stderr[-2000:]


def test_read_it_is_house_1s_catalogue():
    ref = catalogue_of("house1")
    assert isinstance(CATALOGUE, SignalCatalogue)
    assert list(CATALOGUE) == list(ref) and len(CATALOGUE) == len(ref)
    assert CATALOGUE.index("storage.T_sensor_10") == ref.index("storage.T_sensor_10")
    assert "chp.on" in CATALOGUE and CATALOGUE.inputs() == ref.inputs()
    from plant.catalogue import INDEX
    assert INDEX == {s.name: s.index for s in ref}
