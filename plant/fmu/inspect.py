"""Inspect an FMU without running it: FMI version, model, variables with units, platforms with binaries."""
from __future__ import annotations

import zipfile
from dataclasses import dataclass, field
from pathlib import Path

from ..errors import FmuError


@dataclass(frozen=True)
class VariableInfo:
    name: str
    causality: str
    variability: str
    type: str  # Real / Integer / Boolean / String / Float64 / ...
    unit: str  # "" when none is declared
    start: str | None
    description: str
    value_reference: int


@dataclass(frozen=True)
class FmuInfo:
    path: Path
    fmi_version: str
    model_name: str
    model_identifier: str  # of the co-simulation interface ("" when there is none)
    cosimulation: bool
    model_exchange: bool
    platforms: tuple[str, ...]  # fmpy names: linux64, win64, darwin64, ..., c-code (sources only)
    variables: tuple[VariableInfo, ...] = field(repr=False)

    @property
    def this_platform(self) -> str:
        import fmpy

        return fmpy.platform

    @property
    def binary_platforms(self) -> tuple[str, ...]:
        return tuple(p for p in self.platforms if p != "c-code")

    def platform_problem(self) -> str | None:
        """Why the FMU cannot run here, in words; None when it has a binary for this platform."""
        if self.this_platform in self.platforms:
            return None
        have = ", ".join(self.binary_platforms)
        msg = f"no binary for this platform ({self.this_platform})"
        msg += f"; the FMU has binaries for {have} only" if have else "; the FMU has no binaries at all"
        if "c-code" in self.platforms:
            msg += (f"; it ships C sources: build a binary with `fmpy compile {self.path.name}` "
                    "(needs cmake and a C compiler), then use the result")
        return msg

    def variable(self, name: str) -> VariableInfo | None:
        for v in self.variables:
            if v.name == name:
                return v
        return None


def read_model_description(path: Path):
    """fmpy's model description of `path`, with every failure turned into an FmuError naming the file."""
    import fmpy

    if not path.is_file():
        raise FmuError(f"{path}: FMU file not found")
    if not zipfile.is_zipfile(path):
        raise FmuError(f"{path}: not an FMU (not a valid zip archive; is the file truncated or corrupt?)")
    try:
        with zipfile.ZipFile(path) as zf:
            bad = zf.testzip()
            names = set(zf.namelist())
    except (zipfile.BadZipFile, OSError, EOFError) as exc:
        raise FmuError(f"{path}: corrupt zip archive ({exc})") from exc
    if bad is not None:
        raise FmuError(f"{path}: corrupt zip archive (bad CRC in member {bad})")
    if "modelDescription.xml" not in names:
        raise FmuError(f"{path}: not an FMU (no modelDescription.xml in the archive)")
    try:
        return fmpy.read_model_description(str(path), validate=False)
    except Exception as exc:  # fmpy raises plain Exception / lxml errors for malformed XML
        raise FmuError(f"{path}: modelDescription.xml cannot be read ({exc})") from exc


def inspect_fmu(path: str | Path) -> FmuInfo:
    """Read what an FMU declares; FmuError (naming the file) if it is not a readable FMU."""
    import fmpy

    path = Path(path)
    md = read_model_description(path)
    try:
        platforms = tuple(fmpy.supported_platforms(str(path)))
    except Exception as exc:
        raise FmuError(f"{path}: cannot list the binaries ({exc})") from exc
    variables = tuple(
        VariableInfo(
            name=v.name, causality=v.causality or "local", variability=v.variability or "",
            type=v.type or "", unit=(v.unit or (v.declaredType.unit if v.declaredType else None) or ""),
            start=v.start, description=v.description or "", value_reference=v.valueReference,
        )
        for v in md.modelVariables
    )
    cs = md.coSimulation
    return FmuInfo(
        path=path, fmi_version=md.fmiVersion, model_name=md.modelName or "",
        model_identifier=cs.modelIdentifier if cs is not None else "",
        cosimulation=cs is not None, model_exchange=md.modelExchange is not None,
        platforms=platforms, variables=variables,
    )


CAUSALITY_ORDER = {"parameter": 0, "structuralParameter": 0, "calculatedParameter": 1, "input": 2,
                   "output": 3, "independent": 4, "local": 5}


def format_info(info: FmuInfo, causalities: tuple[str, ...] | None = None) -> str:
    """Human-readable report: header, platforms (with a clear line when none fits), variable table."""
    kinds = [k for k, ok in (("co-simulation", info.cosimulation), ("model exchange", info.model_exchange)) if ok]
    lines = [
        f"FMU         {info.path}",
        f"FMI version {info.fmi_version}",
        f"model       {info.model_name} ({', '.join(kinds) or 'no interface declared'})",
        f"platforms   {', '.join(info.platforms) or 'none'}",
    ]
    problem = info.platform_problem()
    lines.append(f"this host   {info.this_platform}: " + ("binary present, can run" if problem is None
                                                          else "CANNOT RUN: " + problem))
    if not info.cosimulation:
        lines.append("note        model exchange only: the twin integrates it with fmpy's solvers "
                     "(FmuModelExchange; solver = \"CVode\" in a house file)")
    rows = [v for v in info.variables if causalities is None or v.causality in causalities]
    rows.sort(key=lambda v: CAUSALITY_ORDER.get(v.causality, 9))
    lines.append(f"variables   {len(rows)} shown of {len(info.variables)}")
    if rows:
        w = max(len(v.name) for v in rows)
        lines.append(f"  {'name':<{w}}  {'causality':<11} {'type':<8} {'unit':<6} {'start':<8} description")
        for v in rows:
            lines.append(f"  {v.name:<{w}}  {v.causality:<11} {v.type:<8} {v.unit or '-':<6} "
                         f"{v.start if v.start is not None else '':<8} {v.description}")
    return "\n".join(lines)


__all__ = ["FmuInfo", "VariableInfo", "inspect_fmu", "format_info", "read_model_description"]
