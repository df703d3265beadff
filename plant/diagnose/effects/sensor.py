"""Sensor candidates (post-processing of one simulated signal): lag, offset, transport delay."""
from __future__ import annotations

import numpy as np

from .base import Effect, Param, register


def first_order(t, y, tau):
    """First-order sensor lag, exact for a linear input between samples... (ZOH on the input)."""
    if tau <= 0:
        return y
    out = np.empty_like(y)
    out[0] = y[0]
    dt = np.diff(t)
    a = np.exp(-dt / tau)
    from scipy.signal import lfilter

    if np.allclose(dt, dt[0]):
        z, _ = lfilter([1 - a[0]], [1, -a[0]], y[1:], zi=[a[0] * y[0]])
        out[1:] = z
        return out
    for i in range(1, len(y)):
        out[i] = a[i - 1] * out[i - 1] + (1 - a[i - 1]) * y[i]
    return out


@register
class SensorLag(Effect):
    id = "sensor_lag"
    component = "sensor"
    kind = "signal"
    params = (Param("tau", 1.0, 3600.0, 0.0, "s", log=True),)
    description = "first-order lag of a temperature sensor (immersion sleeve, thermal contact)"

    def apply(self, t, y, theta):
        return first_order(t, y, float(theta[0]))

    def summary(self, theta, ctx, sim=None):
        return f"sensor time constant {theta[0]:.0f} s"


@register
class SensorOffset(Effect):
    id = "sensor_offset"
    component = "sensor"
    kind = "signal"
    params = (Param("offset", -10.0, 10.0, 0.0, "K"),)
    description = "constant offset of a sensor (calibration)"

    def apply(self, t, y, theta):
        return y + float(theta[0])

    def summary(self, theta, ctx, sim=None):
        return f"sensor offset {theta[0]:+.2f} K"


@register
class TransportDelay(Effect):
    id = "transport_delay"
    component = "sensor"
    kind = "signal"
    params = (Param("delay", 0.0, 1800.0, 0.0, "s"),)
    description = "dead time between the plant and a sensor (pipe transport)"

    def apply(self, t, y, theta):
        d = float(theta[0])
        if d <= 0:
            return y
        return np.interp(t - d, t, y, left=y[0])

    def summary(self, theta, ctx, sim=None):
        return f"transport delay {theta[0]:.0f} s"
