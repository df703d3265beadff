"""labsim shares no code with the twin: every module of plant/labsim is parsed and its imports
checked (relative imports resolved) against the twin's modules and an allow-list."""
import ast
from pathlib import Path

import plant.labsim

PKG = Path(plant.labsim.__file__).parent
FORBIDDEN = ("plant.components", "plant.compiler", "plant.connections", "plant.controllers", "plant.house",
             "plant.housefile", "plant.hydraulics", "plant.truth", "plant.diagnose", "plant.kinds",
             "plant.declaration", "plant.generated", "plant.catalogue", "plant.component", "plant.water",
             "plant.fmu", "plant.sun", "plant.boundary", "plant.schedule", "plant.signals")
ALLOWED_PLANT = ("plant.labsim", "plant.tables", "plant.errors")  # read_tables for plant/data only
ALLOWED_PROFILES = ("profiles.loaders", "profiles.recording")


def _imports(path: Path) -> list[tuple[int, str]]:
    """(line, dotted name) of every import; `from a import b` gives a.b (b may be a module)."""
    tree = ast.parse(path.read_text(), str(path))
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:  # relative to plant/labsim/<module>.py
                base = ["plant", "labsim"][: 2 - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            out += [(node.lineno, f"{mod}.{a.name}") for a in node.names]
    return out


def _within(mod: str, prefixes) -> bool:
    return any(mod == p or mod.startswith(p + ".") for p in prefixes)


def test_no_import_of_the_twin():
    modules = sorted(PKG.glob("*.py"))
    assert len(modules) >= 8
    bad = []
    for f in modules:
        for line, mod in _imports(f):
            if _within(mod, FORBIDDEN):
                bad.append(f"{f.name}:{line}: {mod} (a module of the twin)")
            elif mod.split(".")[0] == "plant" and mod != "plant" and not _within(mod, ALLOWED_PLANT):
                bad.append(f"{f.name}:{line}: {mod} (not on labsim's allow-list)")
            elif mod.split(".")[0] in ("profiles", "gateway") and not _within(mod, ALLOWED_PROFILES):
                bad.append(f"{f.name}:{line}: {mod} (not on labsim's allow-list)")
    assert not bad, "\n".join(bad)


def test_the_checker_sees_relative_imports(tmp_path):
    p = tmp_path / "probe.py"
    p.write_text("from ..house import load_house\nfrom ..components import chp\nfrom .storage import Tank\n"
                 "from plant import compiler\n")
    mods = [m for _, m in _imports(p)]
    assert _within(mods[0], FORBIDDEN) and _within(mods[1], FORBIDDEN) and _within(mods[3], FORBIDDEN)
    assert mods[2] == "plant.labsim.storage.Tank" and _within(mods[2], ALLOWED_PLANT)
