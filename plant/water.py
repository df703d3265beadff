"""Water properties used by every component (one value each, SI units).

The original models mix cp = 4180 (generators) and 4177 J/(kg K) (storage, hydraulics); the
0.07 % difference would break an exact energy ledger, so the whole plant uses one value.
"""
from numba import njit

CP = 4180.0  # J/(kg K)
RHO = 1000.0  # kg/m3: volumes into kg; plant/units.py converts l/min, m3/h ... into kg/s with it


@njit(cache=True)
def density(T):
    """Density of water [kg/m3] at T [degC] (fit to the IAPWS table, 0-100 degC, error < 0.05 kg/m3)."""
    return 1000.0 * (1.0 - (T + 288.9414) / (508929.2 * (T + 68.12963)) * (T - 3.9863) ** 2)

