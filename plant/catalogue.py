"""The signal catalogue of house 1, as its declaration compiles it (`twin signals house1`).

Every house has its own catalogue (House.catalogue); this module keeps house 1's at hand for the
code that is written for house 1's signals (its device maps, the diagnosis's replay, the FMU
export). Names are the stable public interface; order matters only inside one run (indices).

Importing this module compiles nothing: CATALOGUE compiles house 1's declaration when it is first
read (its signals, a name, a length), so `import plant.diagnose` or `twin --help` costs no house.
"""
from .compiler import catalogue_of
from .signals import SignalCatalogue


class _OnFirstUse(SignalCatalogue):
    """A house's catalogue, compiled from its declaration the first time it is read."""

    def __init__(self, house: str):  # noqa: super().__init__ runs in _compiled, on first use
        self._house = house
        self._catalogue: SignalCatalogue | None = None

    def _compiled(self) -> SignalCatalogue:
        if self._catalogue is None:
            self._catalogue = catalogue_of(self._house)
        return self._catalogue

    _by_name = property(lambda self: self._compiled()._by_name)
    _signals = property(lambda self: self._compiled()._signals)


CATALOGUE: SignalCatalogue = _OnFirstUse("house1")


def __getattr__(name: str):
    if name == "INDEX":  # name -> index, as a module attribute read when first asked for
        return {s.name: s.index for s in CATALOGUE}
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
