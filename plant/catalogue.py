"""The signal catalogue of house 1, as its declaration compiles it (`twin signals house1`).

Every house has its own catalogue (House.catalogue); this module keeps house 1's at hand for the
code that is written for house 1's signals (its device maps, the diagnosis's replay, the FMU
export). Names are the stable public interface; order matters only inside one run (indices).
"""
from .compiler import catalogue_of

CATALOGUE = catalogue_of("house1")
INDEX = {s.name: s.index for s in CATALOGUE}
