"""Sensor candidates (post-processing of one simulated signal): lag, offset, transport delay."""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from .base import Effect, Param, register


def first_order(t, y, tau):
    """First-order sensor lag tau dT_s/dt = T - T_s of a signal linear between its samples
    (exact discretisation, first-order hold): over a step dt with a = exp(-dt / tau) and
    b = 1 - (tau / dt)(1 - a), y_s1 = a y_s0 + (1 - a - b) y0 + b y1, starting at y0. Holding each
    interval at its end value instead (y_s1 = a y_s0 + (1 - a) y1) leads the continuous lag by
    about dt / 2: on labsim's continuously lagged top sensor (60 s samples) it fitted 300 s as
    348-368 s."""
    if tau <= 0:
        return y
    return _first_order(np.asarray(t, dtype=np.float64), np.asarray(y, dtype=np.float64), float(tau))


@njit(cache=True)
def _first_order(t, y, tau):
    # compiled: a logger's jittered stamps give every step its own coefficients
    out = np.empty_like(y)
    out[0] = y[0]
    for i in range(1, len(y)):
        dt = t[i] - t[i - 1]
        a = np.exp(-dt / tau)
        b = 1.0 - (tau / dt) * (1.0 - a) if dt > 0.0 else 1.0
        out[i] = a * out[i - 1] + (1.0 - a - b) * y[i - 1] + b * y[i]
    return out


# A temperature sensor lags the water it measures by its own mounting: a PT100 in an immersion
# sleeve or a thermowell with paste, 20 ... 90 s (the rig descriptions' tolerance table,
# docs/lab/house*-rig.md section 5; not chosen on any suite). The twin's sensors read the water
# itself, so a lag or dead time no longer than that is the sensor's mounting, which every lab's
# sensor has, not missing physics (rigsim realisation 3's null_b: a 87 s dead time on the bottom
# tank sensor; labsim realisation 3's no_effect: a 51 s lag on the CHP's outlet sensor).
OWN_LAG_S = 90.0


class _Mounted:
    """A sensor candidate whose size is a time: no longer than OWN_LAG_S it is the sensor's
    mounting, judged on its sensor's own residual (within) or on the whole cost (tolerated)."""

    MOUNTING = "lag"  # what the report calls the fitted time

    def within(self, theta, limit):
        return self.tolerated(theta, None)

    def tolerated(self, theta, ctx):
        seconds = float(theta[0])
        if seconds <= OWN_LAG_S:
            return (f"the {seconds:.0f} s {self.MOUNTING} is within a sensor's own lag in its sleeve or "
                    f"thermowell (<= {OWN_LAG_S:.0f} s)")
        return ""


@register
class SensorLag(_Mounted, Effect):
    id = "sensor_lag"
    component = "sensor"
    kind = "signal"
    params = (Param("tau", 1.0, 3600.0, 0.0, "s", log=True),)
    description = "first-order lag of a temperature sensor (immersion sleeve, thermal contact)"
    # a lag leaves the rate of change times its time constant: small where the tank changes
    # slowly, whatever the lag. One that removes this share of its sensor's held-out residual
    # relative to its neighbours is the sensor's own even within the sensor's mismatch limit
    # (verdict._judged_local). Chosen on rigsim house 2: sensor_lag_bt9 (600 s) removes 60 % of
    # a 0.57 K residual (limit 0.62 K); on null_a no storage sensor's lag removes more than 35 %
    # (at its 3600 s bound; 26 % off it), on house 3's June null 5 %.
    SHAPED_GAIN = 0.5

    def apply(self, t, y, theta):
        return first_order(t, y, float(theta[0]))

    def summary(self, theta, ctx, sim=None):
        return f"sensor time constant {theta[0]:.0f} s"


# An offset is the same whatever the plant does: in every operating state covering at least
# STATE_SHARE of the training samples, the residual the offset was fitted to keeps at least
# CONSTANT_SHARE of it, with its sign. A tank that stratifies differently around a sensor (a
# port plume: rigsim realisation 2's plume_120, storage.T_sensor_2 fitted as a -1.31 K offset)
# differs in some states only: with the boiler on 0.01 of the "offset" was left there, with the
# DHW charge on -0.01. Chosen on that case and on rigsim realisation 1's sensor_offset_p1_5 (a
# true +1.5 K offset on BT_T05: in every state 0.93 ... 1.47 of the fitted one), reported on the
# other offset cases of both simulators and the concealed suite.
STATE_SHARE = 0.05
CONSTANT_SHARE = 0.5


@register
class SensorOffset(Effect):
    id = "sensor_offset"
    component = "sensor"
    kind = "signal"
    params = (Param("offset", -10.0, 10.0, 0.0, "K"),)
    description = "constant offset of a sensor (calibration)"
    same_in_every_state = True

    def apply(self, t, y, theta):
        return y + float(theta[0])

    def solve(self, e, m, shift):
        """The mean residual; with the sensor's height free, the two jointly by least squares on
        [1, gradient], the shift within its tolerance: an offset is constant, a shift's reading
        follows the gradient, so the two separate."""
        m = m & np.isfinite(e)
        if shift is None:
            return float(np.mean(e[m]))
        best = None
        for piece in shift.pieces:  # the reading's pieces (a sensor at the tank's end has two)
            g = piece.g[:len(e)][m]
            A = np.column_stack([np.ones(m.sum()), g])
            (v, d), *_ = np.linalg.lstsq(A, e[m], rcond=None)
            if not piece.lo <= d <= piece.hi:
                d = float(np.clip(d, piece.lo, piece.hi))
                v = float(np.mean(e[m] - d * g))
            sse = float(np.sum((e[m] - v - d * g) ** 2))
            if best is None or sse < best[0]:
                best = (sse, float(v))
        return best[1]

    def stderr(self, e, n_eff):
        return float(np.std(e) / math.sqrt(n_eff))

    def unlike(self, theta, e, states):
        v = float(theta[0])
        ok = np.isfinite(e)
        for name, m in states.items():
            m = m & ok
            if m.sum() < STATE_SHARE * ok.sum() or v == 0.0:
                continue
            share = float(np.mean(e[m])) / v + 0.0  # + 0.0: no "-0.00" in the reason
            if share < CONSTANT_SHARE:
                return (f"not constant: with {name.replace('_', ' ')} the residual keeps {share:.2f} of "
                        f"the {v:+.2f} K offset (< {CONSTANT_SHARE:g})")
        return ""

    def within(self, theta, limit):
        # an offset no larger than the sensor's mismatch limit is a difference a correct replay
        # may leave (rigsim house 2's null_a: -0.55 K on the top sensor against its 0.62 K limit,
        # where the twin's top layer sits above the rig's inlets; a true offset of 2 K: -2.19 K)
        if abs(float(theta[0])) <= limit:
            return f"the {theta[0]:+.2f} K offset is within the sensor's mismatch limit {limit:.2f} K"
        return ""

    def summary(self, theta, ctx, sim=None):
        return f"sensor offset {theta[0]:+.2f} K"


@register
class TransportDelay(_Mounted, Effect):
    id = "transport_delay"
    component = "sensor"
    kind = "signal"
    params = (Param("delay", 0.0, 1800.0, 0.0, "s"),)
    description = "dead time between the plant and a sensor (pipe transport)"
    MOUNTING = "dead time"

    def apply(self, t, y, theta):
        d = float(theta[0])
        if d <= 0:
            return y
        return np.interp(t - d, t, y, left=y[0])

    def summary(self, theta, ctx, sim=None):
        return f"transport delay {theta[0]:.0f} s"
