"""The storage's ports: the layer a port's height falls in, and the ports that carry a flow in a
step (storage.step's advection and substep count).

A tank's port list is long and mostly idle: every coupling point with an inlet-mixing zone
(switch.storage_inlet_mixing) gives it one slot per layer of the zone, forty of them on house 2,
and all but the one the inflow enters carry 0 kg/s. The advection sums the port flows of each
layer for every face of every substep (layers x ports), which made the port scan a third of the
storage's step. Leaving the idle ports out changes no computed value: a face's flow plus 0.0 is
the same flow (only the sign of a zero flow could differ, and a zero flow is tested by its
comparisons with 0.0 alone); the flowing ports keep their order, so every sum adds the same
terms in the same order. The kept ports go into scratch arrays the plant allocates once (two
arrays allocated per call were an eighth of a small plant's step).
"""
from __future__ import annotations

from numba import njit

from ..errors import ConfigError


def port_layer(height_m: float, params) -> int:
    """Layer index (0 = top) that contains a port at height_m above the tank bottom (params: a
    storage's Params)."""
    H = params.height
    if not (0.0 <= height_m <= H):
        raise ConfigError(f"port height {height_m} m: outside the tank; allowed 0 … {H} m")
    from_bottom = min(int(height_m / H * params.n_layers), params.n_layers - 1)
    return params.n_layers - 1 - from_bottom


@njit(cache=True)
def flowing(layer, m, keep_layer, keep_m):
    """The ports whose flow is not 0.0 (NaN kept), in their order, into keep_layer and keep_m
    (scratch of the ports' length: a step allocates nothing); returns their count."""
    c = 0
    for i in range(layer.shape[0]):
        if m[i] != 0.0:
            keep_layer[c] = layer[i]
            keep_m[c] = m[i]
            c += 1
    return c
