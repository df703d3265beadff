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
arrays allocated per call were an eighth of a small plant's step). The substep count's largest
outflow and the advection's face flows, for the same reason, change at port layers only
(worst_outflow, next_port_layer): the layers between are not scanned for ports.
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


@njit(cache=True, inline="always")
def worst_outflow(N, in_layer, in_m, out_layer, out_m):
    """The largest mass flow [kg/s] leaving one of N layers (ports and faces), the face flows
    summed downward from the top. Between two port layers every face carries the same flow, so
    the layers are visited port layer by port layer (a few ports: a few visits, not N): each
    value is the one the layer-by-layer sum gives, to the last bit (tests/plant/test_storage.py)."""
    nin = in_layer.shape[0]
    nout = out_layer.shape[0]
    worst = 0.0
    F_above = 0.0
    k = -1
    while k < N - 1:
        nxt = min(next_port_layer(k, N, in_layer, out_layer), N - 1)  # the bottom layer: no face below
        if nxt > k + 1:  # layers without a port: each passes on the face flow above it
            F = F_above + 0.0
            out = _leaving(0.0, F, F_above)
            if out > worst:  # (a NaN flow's outflow is never the largest)
                worst = out
            F_above = F
        k = nxt
        net = 0.0
        outk = 0.0
        for i in range(nin):
            if in_layer[i] == k:
                net += in_m[i]
        for j in range(nout):
            if out_layer[j] == k:
                net -= out_m[j]
                outk += out_m[j]
        F = F_above + net if k < N - 1 else 0.0
        out = _leaving(outk, F, F_above)
        if out > worst:
            worst = out
        F_above = F
    return worst


@njit(cache=True, inline="always")
def _leaving(outk, F, F_above):
    """What leaves a layer: its ports' outflow outk, the face below when it flows down (F > 0),
    the face above when it flows up (F_above < 0)."""
    if F > 0.0:
        outk += F
    if F_above < 0.0:
        outk -= F_above
    return outk


@njit(cache=True, inline="always")
def next_port_layer(k, N, in_layer, out_layer):
    """The first layer below layer k that has a port; N when none."""
    nxt = N
    for i in range(in_layer.shape[0]):
        if k < in_layer[i] < nxt:
            nxt = in_layer[i]
    for j in range(out_layer.shape[0]):
        if k < out_layer[j] < nxt:
            nxt = out_layer[j]
    return nxt
