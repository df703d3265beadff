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
