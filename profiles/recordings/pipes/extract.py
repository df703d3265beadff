"""Re-create the pipe recordings in this folder from a git mirror of the Modelica Buildings library.

    python3 profiles/recordings/pipes/extract.py /path/to/modelica-buildings.git [COMMIT]

Reads the published measurement tables (`Buildings/Resources/Data/.../PlugFlowPipes/*.mos`), the
pipe data of the validation models (PlugFlowULg.mo, PlugFlowAIT.mo, Data/*.mo, transcribed into
each pipe.toml by hand, see NOTICE) and the published Dymola results of those models
(ReferenceResults), and writes per test: recording.csv, and modelica_reference.csv where the
library publishes the plug-flow pipe's own outlet trajectory for that test.
"""
from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

HERE = Path(__file__).parent
DATA = "Buildings/Resources/Data/Fluid/FixedResistances/Validation/PlugFlowPipes/"
REF = "Buildings/Resources/ReferenceResults/Dymola/Buildings_Fluid_FixedResistances_Validation_PlugFlowPipes_"
ULG = ("150801", "151202", "151204_1", "151204_2", "151204_4", "160104_2", "160118_1")


def show(git: str, commit: str, path: str) -> str:
    return subprocess.run(["git", "--git-dir", git, "show", f"{commit}:{path}"], check=True,
                          capture_output=True, text=True).stdout


def table(text: str) -> list[list[float]]:
    rows = []
    for line in text.splitlines():
        line = line.strip()
        if line and (line[0].isdigit() or line[0] in "-."):
            rows.append([float(v) for v in line.replace(",", " ").split()])
    return rows


def fmt(v: float) -> str:
    return repr(round(v, 6)).rstrip("0").rstrip(".") if v != int(v) else str(int(v))


def write(path: Path, header: list[str], rows) -> None:
    path.write_text(",".join(header) + "\n" + "".join(",".join(fmt(v) for v in r) + "\n" for r in rows))


def reference(git: str, commit: str, model: str, names: list[str]) -> tuple[list[float], dict]:
    """A published Dymola result: time = [t0, t1] and 101 equidistant values per variable."""
    text = show(git, commit, REF + model + ".txt")
    series = {}
    for name, values in re.findall(r"^(\S+)=\[([^\]]*)\]", text, flags=re.M):
        series[name] = [float(v) for v in values.split(",")]
    t0, t1 = series["time"]
    n = len(series[names[0]])
    return [t0 + (t1 - t0) * i / (n - 1) for i in range(n)], {k: series[k] for k in names}


ULG_COLUMNS = """# ULg pipe test {test}: published columns of PipeDataULg{test}.mos (see NOTICE)
[recording]
start = "{date}"
file = "recording.csv"
time = "time"

[columns]
"m_flow" = {{ signal = "pipe.m_flow", unit = "kg/s" }}        # column 2: mass flow rate
"T_out" = {{ signal = "pipe.T_out", unit = "degC" }}          # column 4: outlet water temperature
"T_in" = {{ signal = "pipe.T_in", unit = "degC" }}            # column 6: inlet water temperature
"T_in_pipe" = {{ signal = "pipe.T_wall_in", unit = "degC" }}  # column 5: "inlet pipe temperature"
{wall_out}"""

ULG_PIPE = """# The ULg test bench pipe as PlugFlowULg.mo declares it (the record PipeDataULg documents the bench:
# "Thickness 3.91 mm (outer diameter 0.0603 m)", "metal density about 7800 kg/m3", "specific heat
# capacity about 480 J/kg/K", insulation Tubolit 60/13, 13 mm, "nominal thermal coefficient inferior
# 0.04 ... the insulation is quite aged", outside heat transfer coefficient assumed 5 W/m2K).
[pipe]
T_env = 18.0      # degC, "During the test, the ambient temperature is equal to 18 degC" (the model's heat port: 22 degC)
T_init = {T_init}   # degC, T_start_out of PipeDataULg{test}: pipe and water start at the water's temperature
inlet = "pipe.T_in"
outlet = "pipe.T_out"

[[segment]]
name = "pipe"
length = 39.0                    # m
inner_diameter = 0.05248         # m (dh)
wall_thickness = 0.0039          # m (thickness)
wall_density = 8000.0            # kg/m3 (rhoPip)
wall_cp = 500.0                  # J/(kg K) (cPip)
outer_diameter = 0.0603          # m, of the steel pipe
insulation_thickness = 0.013     # m (dIns)
insulation_conductivity = 0.04   # W/(m K) (kIns)
outer_h = 5.0                    # W/(m2 K), insulation surface to ambient
U = {U}              # W/(m K) = 1/R, R as PlugFlowULg.mo computes it from the four lines above
flow = ["pipe.m_flow"]
"""

AIT_COLUMNS = """# AIT network week (23-29 January 2009): published columns of PipeDataAIT151218.mos (see NOTICE)
[recording]
start = "2009-01-23"
file = "recording.csv"
time = "time"

[columns]
"T_p1" = { signal = "pipe.T_in", unit = "K" }       # point 1 (the plant side): the path's inlet
"T_p2" = { signal = "pipe.T_out", unit = "K" }      # point 2: the path's outlet
"T_p3" = { signal = "point3.T", unit = "K" }
"T_p4" = { signal = "point4.T", unit = "K" }
"m_p1" = { signal = "point1.m_flow", unit = "kg/s" }
"m_p2" = { signal = "point2.m_flow", unit = "kg/s" }
"m_p3" = { signal = "point3.m_flow", unit = "kg/s" }
"m_p4" = { signal = "point4.m_flow", unit = "kg/s" }
"T_air" = { signal = "pipe.T_env", unit = "K" }     # outdoor temperature: the model's boundary of the buried pipes
"""

AIT_PIPE = """# The AIT path from point 1 to point 2 as PlugFlowAIT.mo declares its pipes (pip0, pip1, pip5,
# pip2 in series; at each junction the flow of the branches not on the path leaves). Pipes buried
# (soil 2.4 W/(m K), 1 m deep in the model's R), polyurethane insulation 0.024 W/(m K); steel wall
# 3.2 mm, cPip = 500 J/(kg K), rhoPip = 8000 kg/m3. The record PipeDataAIT151218 gives DN80, casing
# 0.18 m and a length-specific heat loss coefficient of 0.208 W/(m K).
[pipe]
T_env_signal = "pipe.T_env"   # the outdoor temperature, as the model's prescribed boundary
inlet = "pipe.T_in"
outlet = "pipe.T_out"
# no T_init: "the pipes' temperatures are not initialized" (PlugFlowAIT.mo)

[[segment]]
name = "pip0"
length = 20.0
inner_diameter = 0.0825
wall_thickness = 0.0032
wall_density = 8000.0
wall_cp = 500.0
U = {U80}   # 1/R, R = ln(0.18/0.0899)/(2 pi 0.024) + ln(2/0.18)/(2 pi 2.4)
flow = ["point1.m_flow"]

[[segment]]
name = "pip1"
length = 115.0
inner_diameter = 0.0825
wall_thickness = 0.0032
wall_density = 8000.0
wall_cp = 500.0
U = {U80}
flow = ["point2.m_flow", "point3.m_flow", "point4.m_flow"]

[[segment]]
name = "pip5"
length = 20.0
inner_diameter = 0.0825
wall_thickness = 0.0032
wall_density = 8000.0
wall_cp = 500.0
U = {U80}
flow = ["point2.m_flow", "point3.m_flow"]

[[segment]]
name = "pip2"
length = 76.0
inner_diameter = 0.0273    # 0.0337 - 2 x 0.0032
wall_thickness = 0.0032
wall_density = 8000.0
wall_cp = 500.0
U = {U25}   # 1/R80 of the model: ln(0.07/0.0337)/(2 pi 0.024) + ln(2/0.07)/(2 pi 2.4)
flow = ["point2.m_flow"]
"""

DATES = {"150801": "2015-08-01", "151202": "2015-12-02", "151204_1": "2015-12-04", "151204_2": "2015-12-04",
         "151204_4": "2015-12-04", "160104_2": "2016-01-04", "160118_1": "2016-01-18"}


def u_values(git: str, commit: str) -> dict:
    """Start temperatures of each ULg record, and the loss coefficients the models compute."""
    import math
    out = {}
    for test in ULG:
        rec = show(git, commit, f"Buildings/Fluid/FixedResistances/Validation/PlugFlowPipes/Data/PipeDataULg{test}.mo")
        out[test] = float(re.search(r"T_start_out=([0-9.]+)", rec).group(1))
    k, d, do = 0.04, 0.013, 0.0603
    r_ulg = (1 / (2 * k) * math.log((do / 2 + d) / (do / 2)) + 1 / (5 * (do + 2 * d))) / math.pi
    r80 = math.log(0.18 / 0.0899) / (2 * math.pi * 0.024) + math.log(2 / 0.18) / (2 * math.pi * 2.4)
    r25 = math.log(0.07 / 0.0337) / (2 * math.pi * 0.024) + math.log(2 / 0.07) / (2 * math.pi * 2.4)
    out["U"] = {"ULg": round(1 / r_ulg, 5), "80": round(1 / r80, 5), "25": round(1 / r25, 5)}
    return out


def main(git: str, commit: str = "HEAD") -> None:
    u = u_values(git, commit)
    for test in ULG:
        rows = table(show(git, commit, DATA + f"PipeDataULg{test}.mos"))
        d = HERE / f"ULg{test}"
        d.mkdir(exist_ok=True)
        wall_out = any(r[2] != 0.0 for r in rows)   # column 3 is all 0 where it was not recorded
        header = ["time", "m_flow", "T_out", "T_in", "T_in_pipe"] + (["T_out_pipe"] if wall_out else [])
        write(d / "recording.csv", header,
              [[r[0], r[1], r[3], r[5], r[4]] + ([r[2]] if wall_out else []) for r in rows])
        extra = '"T_out_pipe" = { signal = "pipe.T_wall_out", unit = "degC" }  # column 3: "outlet pipe temperature"\n'
        (d / "columns.toml").write_text(ULG_COLUMNS.format(test=test, date=DATES[test], wall_out=extra if wall_out else
                                                           "# column 3 (outlet pipe temperature) is all 0 in this test: not recorded\n"))
        (d / "pipe.toml").write_text(ULG_PIPE.format(test=test, T_init=u[test], U=u["U"]["ULg"]))
    t, ref = reference(git, commit, "PlugFlowULg", ["senTem_out.T"])
    write(HERE / "ULg151202" / "modelica_reference.csv", ["time", "T_out"],
          [[ti, v - 273.15] for ti, v in zip(t, ref["senTem_out.T"])])
    rows = table(show(git, commit, DATA + "PipeDataAIT151218.mos"))
    d = HERE / "AIT151218"
    d.mkdir(exist_ok=True)
    (d / "columns.toml").write_text(AIT_COLUMNS)
    (d / "pipe.toml").write_text(AIT_PIPE.format(U80=u["U"]["80"], U25=u["U"]["25"]))
    write(d / "recording.csv", ["time", "T_p1", "T_p2", "T_p3", "T_p4", "m_p1", "m_p2", "m_p3", "m_p4", "T_air"], rows)
    t, ref = reference(git, commit, "PlugFlowAIT", ["senTem_p2.T"])
    write(d / "modelica_reference.csv", ["time", "T_out"], [[ti, v - 273.15] for ti, v in zip(t, ref["senTem_p2.T"])])


if __name__ == "__main__":
    main(*sys.argv[1:])
