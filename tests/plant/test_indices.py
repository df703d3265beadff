"""Positions in the packed parameter vector and the state vector come from the declarations (#27).

Every kind (plant/components, plant/controllers, plant/connections) declares them as
`P = indices(Params)` / `X = indices(STATES)`, so they cannot disagree with the field order by
construction; this checks the helper once and that no kind module writes positions by hand again
(`A, B = range(2)`, `I_A = 0`, `X_A = 0`).
"""
import ast
import dataclasses
import importlib
import pkgutil
from pathlib import Path

import pytest

import plant
from plant.component import indices, pack

ROOT = Path(plant.__file__).parent
KINDS = sorted(f"{package}.{m.name}" for package in ("components", "controllers", "connections")
               for m in pkgutil.iter_modules([str(ROOT / package)]))


def namespaces(mod):
    """The module's position namespaces made by indices(): {global name: namespace}."""
    return {k: v for k, v in vars(mod).items()
            if isinstance(v, tuple) and type(v).__module__ == "plant.component"}


def test_indices_are_the_pack_order_and_the_state_order():
    @dataclasses.dataclass(frozen=True)
    class Params:
        a: float = 3.0
        b: int = 4
        c: bool = True

    P, X = indices(Params), indices(("T", "E_heat"))
    assert (P.a, P.b, P.c, len(P)) == (0, 1, 2, 3) and (X.T, X.E_heat) == (0, 1)
    p = pack(Params())
    assert [p[i] for i in P] == [3.0, 4.0, 1.0]


@pytest.mark.parametrize("name", KINDS)
def test_kind_positions_are_derived_from_its_declarations(name):
    mod = importlib.import_module(f"plant.{name}")
    declared = {}  # declaration -> its names in order
    for k, v in vars(mod).items():
        if dataclasses.is_dataclass(v) and isinstance(v, type) and v.__module__ == mod.__name__:
            declared[v] = tuple(f.name for f in dataclasses.fields(v))
        elif k.endswith("STATES"):
            declared[v] = tuple(v)
    for key, ns in namespaces(mod).items():
        assert tuple(ns) == tuple(range(len(ns))), key
        sources = [d for d, names in declared.items() if names == ns._fields]
        assert sources, f"{name}.{key} matches no Params class or STATES of the module"
        for d in sources:
            if isinstance(d, type):  # a Params class: its defaults packed land where P says
                values = d()
                p = pack(values)
                assert all(p[i] == float(getattr(values, f)) for f, i in zip(ns._fields, ns)), key
    tree = ast.parse((ROOT / (name.replace(".", "/") + ".py")).read_text())
    by_hand = [node.lineno for node in tree.body if isinstance(node, ast.Assign)
               and (isinstance(node.value, ast.Call) and getattr(node.value.func, "id", "") == "range"
                    or any(getattr(t, "id", "").startswith(("I_", "X_")) for t in node.targets))]
    assert not by_hand, f"plant/{name}.py:{by_hand}: positions written by hand; use indices()"

