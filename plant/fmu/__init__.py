"""FMUs in the twin (fmpy): import co-simulation and model-exchange FMUs, export the native house.

  inspect.py    read an FMU without running it (version, platforms with binaries, variables/units)
  component.py  the ONE fmpy adapter: bindings signal <-> FMU variable with unit conversion; every
                failure is an FmuError naming the file and variable.
                  FmuComponent      FMI 2.0 / 3.0 co-simulation, step(dt) = doStep
                  FmuModelExchange  FMI 2.0 model exchange, step(dt) integrates with fmpy's
                                    CVodeSolver or ForwardEuler (inputs held, events handled)
                  open_fmu          picks one of the two for a file
  house.py      FmuHouse: the whole plant is one FMU ([house] topology = "fmu" in a house file),
                with the House API the gateway uses (catalogue = the bound signals)
  build.py      compile the C FMUs with gcc: storage_c/ (the native storage kernel, FMI 2.0 CS)
                and lag_c/ (a first-order heat lag as FMI 2.0 ME and FMI 3.0 CS test FMUs)
  export.py     `twin export-fmu`: the native twin as an FMI 2.0 co-simulation FMU (pythonfmu);
                the FMU imports the installed twin, so it needs a Python with this package

Where an FMU runs in a house:
  - a storage: `kind = "storage_fmu"`, `fmu = "..."` with `[<name>.bindings]` and
    `[<name>.parameters]` (storage_kind.py); the compiled step calls its doStep in object mode
    at the storage's place in the step, so clock, step order and ledger stay the house's.
  - the whole plant: `[house] topology = "fmu"`, `fmu = "..."`, `[bindings]` catalogue signal =
    FMU variable (or { var, unit }), optional `[parameters]`, `solver = "CVode" | "Euler"` for a
    model-exchange FMU, `max_step`; load_house returns an FmuHouse, stepped by the gateway's clock
    (lock-step, paced, accelerated) like the native house.  No snapshot/restore or energy ledger.
Not done: FMI 3.0 model exchange, FMI 1.0, array variables, Integer/Boolean signal bindings.
"""
