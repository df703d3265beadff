"""FMU support: inspect FMUs, run a co-simulation FMU as a plant component, build the storage FMU."""
