"""The command line is on top (#27): cli/ imports the packages, none of them imports cli/."""
import ast
from pathlib import Path

import cli

ROOT = Path(cli.__file__).resolve().parent.parent
BELOW = ("plant", "gateway", "district", "devices", "profiles", "phil", "labsim", "rigsim")


def _imports_of_cli(path: Path) -> list[str]:
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and not node.level:
            names = [node.module or ""]
        elif (isinstance(node, ast.Call) and node.args and isinstance(node.args[0], ast.Constant)
              and getattr(node.func, "attr", getattr(node.func, "id", "")) in ("import_module", "__import__")):
            names = [str(node.args[0].value)]
        else:
            continue
        found += [f"{path}:{node.lineno}: {n}" for n in names
                  if n == "cli" or n.startswith("cli.")]
    return found


def test_the_command_line_is_a_top_level_package_with_its_entry_point():
    assert Path(cli.__file__).resolve().parent == ROOT / "cli" and (ROOT / "cli" / "main.py").is_file()
    assert not (ROOT / "gateway" / "cli").exists()


def test_no_package_below_imports_the_command_line():
    files = [f for pkg in BELOW for f in sorted((ROOT / pkg).rglob("*.py"))]
    assert len(files) > 100
    bad = [hit for f in files for hit in _imports_of_cli(f)]
    assert not bad, "\n".join(bad)


def test_the_checker_sees_an_import_of_the_command_line(tmp_path):
    p = tmp_path / "probe.py"
    p.write_text("import cli.main\nfrom cli import serve\nimport importlib\nimportlib.import_module('cli.kpi')\n"
                 "import click\nfrom gateway import clock\n")
    assert len(_imports_of_cli(p)) == 3
