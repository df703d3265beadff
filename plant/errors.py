"""The project's error hierarchy: one root, one subclass per kind of bad input."""


class TwinError(Exception):
    """Root of every error the project raises on purpose."""


class ConfigError(TwinError):
    """A house file, scenario or mapping file is wrong (message names file, key and fix)."""


class SignalError(TwinError):
    """An unknown or misused signal name."""


class DeviceMapError(TwinError):
    """A device map is inconsistent."""


class TransportError(TwinError):
    """A transport could not be set up."""


class FmuError(TwinError):
    """An FMU cannot be loaded, bound or stepped."""


class DataError(TwinError):
    """A shipped or user data file is malformed."""


def closest(name, names, n: int = 3, cutoff: float = 0.6) -> list[str]:
    """The valid names nearest to a bad one, best first (difflib's ratio): every "did you mean"
    and "closest" of a message comes from here, so they all rank alike."""
    from difflib import get_close_matches

    return get_close_matches(str(name), list(names), n=n, cutoff=cutoff)


def did_you_mean(name, names, otherwise: str, n: int = 3, cutoff: float = 0.6) -> str:
    """"did you mean a, b?" with the closest names, or `otherwise` (the valid names, a next step)
    when none is close."""
    close = closest(name, names, n, cutoff)
    return f"did you mean {', '.join(close)}?" if close else otherwise
