"""What is read off a stratified storage's layer temperatures outside the compiled step: the state
of charge, the stored energy and the temperatures at sensor heights (the layers and their
kernel: plant/components/storage.py; the house's SOC, E_stored and T_sensor_* signals are
emitted by plant/components/storage_kind.py from the storage's soc_T0/soc_Tmax parameters).

State of charge
---------------
The reference (section 7.4) has three definitions:
  (a) inside the ProHMo storage model: SOC = sum(T_i - T_env) / sum(T_max - T_env), T_env = 18 degC;
  (b) the house controllers (SF1.mo): SOC = (mean(T) - T_0) / (T_max - T_0), buffer 40/80 degC,
      DHW tank 15/80 degC;
  (c) the SiL export of SF1 overrides (b) with 20/95 degC (buffer) and 40/80 degC (DHW).
We use (b), the definition the house-1 controller thresholds (CHP on below 0.60, off above 0.95;
boiler on below 0.50, off above 0.65) were tuned for: `soc(T, 40, 80)` for the buffer
(SOC_BUFFER) and `soc(T, 15, 80)` for the DHW tank (SOC_DHW, the built-in SF1.mo definition).
The SOC is not clipped (it is < 0 below a mean of T_0 and > 1 above T_max).
`stored_energy(T, params, T_ref)` = CP RHO V/N sum(T - T_ref) [J].

Sensors: `sensor_temperatures(T, n)` interpolates the layer-centre temperatures linearly to n
equally spaced sensor heights (i - 0.5) H / n, i = 1 (bottom) ... n (top) - the lab's
TS_S_TM_BT_1..10 (ProHMo: sensor i = layer i of 10); returned bottom first.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..water import CP, RHO
from .storage import Params
from .storage_kind import sensors

SOC_BUFFER = (40.0, 80.0)  # T_0, T_max [degC] of the house-1 buffer controller SOC
SOC_DHW = (15.0, 80.0)  # T_0, T_max [degC] of the house-1 DHW-tank SOC (SF1.mo)


@njit(cache=True)
def soc(T, T_0, T_max):
    """House-controller state of charge (mean(T) - T_0) / (T_max - T_0), not clipped."""
    return (np.mean(T) - T_0) / (T_max - T_0)


def stored_energy(T, params: Params, T_ref: float) -> float:
    """Energy stored above T_ref [J]: CP RHO V/N sum(T - T_ref)."""
    T = np.asarray(T, dtype=np.float64)
    return float(CP * RHO * params.volume / len(T) * np.sum(T - T_ref))


@njit(cache=True)
def sensor_temperatures_into(T, out):
    """Fill out[i] with the temperature at sensor i+1 of len(out) equally spaced sensors (sensor 1
    = out[0] the lowest, at H/(2n)): the readings the compiled step writes (storage_kind.sensors)."""
    sensors(T, out, 0, out.shape[0])
    return out


@njit(cache=True)
def sensor_temperatures(T, n_sensors=10):
    """Temperatures at n equally spaced sensor heights, sensor 1 = bottom first (lab TS_S_TM_BT_1..n)."""
    out = np.empty(n_sensors, dtype=np.float64)
    return sensor_temperatures_into(T, out)


__all__ = ["soc", "stored_energy", "sensor_temperatures", "sensor_temperatures_into", "SOC_BUFFER", "SOC_DHW"]
