"""`twin houses list`: the shipped houses, one line each (name, laboratory name, generators,
storages, emitters), read from their house files without compiling them."""
from __future__ import annotations

import argparse

EXAMPLES = """examples:
  twin houses list                    # the five CoSES houses
  twin houses list --variants         # also the variants (house1_solar, house1_truth ...)
  twin simulate SF3 --days 2          # a laboratory name works wherever a house is named
"""

GENERATOR_KINDS = ("chp", "boiler", "heat_pump_air", "heat_pump_brine", "solar_collector", "pv", "electric_heater")


def register(sub) -> None:
    p = sub.add_parser("houses", help="list the shipped houses",
                       description="The shipped house files with their generators, storages and "
                                   "emitters.\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    verbs = p.add_subparsers(dest="verb", metavar="VERB")
    ls = verbs.add_parser("list", help="one line per house", description=EXAMPLES,
                          formatter_class=argparse.RawDescriptionHelpFormatter)
    ls.add_argument("--variants", action="store_true", help="also list variant files")
    ls.set_defaults(func=run_list)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


def describe(name: str) -> str:
    """One line: name, alias, generators, storages, emitters of a shipped house."""
    from plant.declaration import load
    from plant.housefile import alias_of

    decl = load(name)
    gens, stores, emitters = [], [], []
    for inst in decl.instances.values():
        prm = inst.params
        if inst.kind in GENERATOR_KINDS:
            size = {"chp": "P_el_max", "boiler": "P_nom", "pv": "P_peak", "electric_heater": "P_nom",
                    "heat_pump_air": "P_heat_nom", "heat_pump_brine": "P_heat_nom"}.get(inst.kind)
            detail = f" {getattr(prm, size) / 1000:g} kW" if size else f" {prm.area:g} m2" if inst.kind == "solar_collector" else ""
            gens.append(f"{inst.name} ({inst.kind}{detail})")
        elif inst.kind in ("storage", "storage_fmu"):
            stores.append(f"{inst.name} {prm.volume * 1000:.0f} l")
        elif inst.kind in ("radiator", "floor_heating"):
            emitters.append(f"{inst.name} ({inst.kind} {prm.Q_nominal / 1000:.1f} kW)")
    return (f"{name:<18} {alias_of(name) or '-':<4} generators: {', '.join(gens) or '-'}; "
            f"storage: {', '.join(stores) or '-'}; emitters: {', '.join(emitters) or '-'}")


def run_list(args) -> int:
    from plant.housefile import ALIASES, shipped

    names = list(ALIASES.values())
    if args.variants:
        names += [n for n in shipped() if n not in names]
    for name in names:
        print(describe(name))
    return 0
