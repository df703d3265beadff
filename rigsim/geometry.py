"""The discretisation shared by rigsim's houses: how inflow ports, wall losses and coils spread
over the cells of a water column, the pipe sensors' water, and the steps and time stamps of a run."""
from __future__ import annotations

import math

import numpy as np

from .layout import CP


def _window_weights(n, dz, centre, volume_m3, area, H):
    """Weights (sum 1) of the cells overlapping a band of the given volume around a height."""
    span = volume_m3 / area
    w = np.zeros(n)
    if span <= dz:
        w[min(n - 1, max(0, int(centre / dz)))] = 1.0
        return w
    lo, hi = centre - span / 2, centre + span / 2
    if lo < 0.0:
        lo, hi = 0.0, span
    if hi > H:
        lo, hi = max(0.0, H - span), H
    edges = np.arange(n + 1) * dz
    w = np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, None)
    return w / w.sum()


def _cell_UA(n, d, H, UA):
    dz = H / n
    side = math.pi * d * dz
    end = math.pi * d * d / 4
    a = np.full(n, side)
    a[0] += end
    a[-1] += end
    return UA * a / a.sum()


def coil_weights(n, dz, H, top, bottom, shift, length_factor, n_seg):
    """Weights [n_seg, n] (each row sums to 1) of the cells of a column (n cells of height dz,
    water height H) that each segment of a coil lies over, segments from the coil's top (its
    inlet) down: the datasheet coil (top, bottom) shifted by shift and stretched by
    length_factor about its middle, clipped to the water column."""
    c_mid = 0.5 * (bottom + top) + shift
    c_len = (top - bottom) * length_factor
    c_top = min(H, c_mid + c_len / 2)
    seg_h = c_len / n_seg
    edges = np.arange(n + 1) * dz
    W = np.zeros((n_seg, n))
    for k in range(n_seg):
        hi = c_top - k * seg_h
        lo = max(0.0, hi - seg_h)
        w = np.clip(np.minimum(edges[1:], hi) - np.maximum(edges[:-1], lo), 0.0, None)
        W[k] = w / w.sum()
    return W


def pipe_sensors(nz, names, cp=CP):
    """Heat capacity [J/K] of the pipe water around each named pipe sensor (the realisation's
    water mass, 30 % added for the pipe wall) and its loss coefficient [W/K] from its cooling
    time constant."""
    C = np.array([nz["pipe_sensor_water_kg"][k] * cp * 1.3 for k in names])
    UA = np.array([C[i] / (60.0 * nz["pipe_cooling_tau_min"][k]) for i, k in enumerate(names)])
    return C, UA


def sample_grid(spinup_days, days, dt, jitter_seed, rng_key=()):
    """The steps and the logger's time stamps: spin-up [s], the first logged step, the number of
    steps (the window and 2 s), the minutes of inputs needed from the spin-up's start, the time
    stamps t_s (one a minute, +-0.5 s jitter drawn from jitter_seed and rng_key) and the step
    of each stamp."""
    spin = spinup_days * 86400.0
    log_step = int(round(spin / dt))
    n_steps = log_step + int(round(days * 86400.0 / dt)) + int(round(2.0 / dt))
    n_min = int((spin + days * 86400.0) / 60.0) + 4
    n_samp = int(round(days * 1440))
    rng = np.random.default_rng([int(jitter_seed), 7, *rng_key])
    t_s = 60.0 * np.arange(n_samp) + rng.uniform(-0.5, 0.5, n_samp)
    t_s[0] = abs(t_s[0])
    t_s = np.round(t_s, 3)
    sample_steps = log_step + np.round(t_s / dt).astype(np.int64)
    return spin, log_step, n_steps, n_min, t_s, sample_steps

