"""FMI co-simulation for the twin (fmpy).

  inspect.py    read an FMU without running it (version, platforms with binaries, variables/units)
  component.py  FmuComponent, the ONE fmpy adapter: bindings signal <-> FMU variable with unit
                conversion; every failure is an FmuError naming the file and variable
  build.py      compile storage_c/ (the native storage kernel in C) into an FMI 2.0 CS .fmu
  storage_c/    C sources + modelDescription.xml of that FMU
  export.py     `twin export-fmu`: the native twin as an FMI 2.0 co-simulation FMU (pythonfmu);
                the FMU imports the installed twin, so it needs a Python with this package

A house's heating storage can run as an FMU: `[storage] fmu = "..."` with `[storage.bindings]`
and `[storage.parameters]` in the house file (syntax: plant/housefile.py); House then steps
solver.before_storage -> FmuComponent.step -> solver.after_storage every internal step
(plant/house.py, FmuStorage; tests/plant/test_house_fmu.py).
Not done yet: a whole plant (a user's house FMU) in place of the native house.
"""
