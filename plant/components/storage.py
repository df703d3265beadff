"""Stratified hot-water storage tank (house 1: 800 l heating buffer, 500 l DHW tank).

Physics in words
----------------
The tank is a vertical column of N layers of equal volume V/N (layer 0 = TOP, layer N-1 = bottom),
each perfectly mixed, with temperature T_k.  One call of `step` advances all layers by dt with an
explicit, energy-conservative finite-volume scheme, split into equal substeps when needed:

1. Advection.  Direct ports inject water into their layer (at the port's temperature) or withdraw
   it from their layer (at the layer's temperature).  Water is incompressible, so the net vertical
   mass flow F_k across the interface below layer k is the cumulative sum from the top of
   (inflows - outflows); F > 0 is downward.  The enthalpy carried across an interface is
   F_k * CP * T_face with a flux-limited (TVD) face temperature of Lax-Wendroff/Sweby type,
       T_face = T_U + 0.5 * phi(r) * (1 - nu) * (T_D - T_U),  r = (T_U - T_UU) / (T_D - T_U),
   (U = upwind layer, D = downwind layer, UU = the one further upwind, nu = |F| dt / m_layer),
   with the superbee limiter by default (`limiter` parameter: 0 = first-order upwind as in the
   original ProHMo model, 1 = van Leer, 2 = monotonized central, 3 = superbee).  The original's
   upwind shift smears the thermocline by about one 16 cm layer per passage (reference 7.6 and
   15.3); the limited scheme keeps a charging front about 3 layers wide, most of which is the
   inlet layer's own mixing (measured figures below).  Superbee was chosen over MC after
   measuring: it is sharper (3.2 vs 4.5 layers) and did not over-steepen smooth profiles in
   trials (tanh fronts 3.3 / 6.0 / 12.0 layers wide, moved 10-20 layers at 10 l/min: 3.3 / 5.9 /
   11.7 layers afterwards; MC gave 4.3 / 6.6 / 12.0).
2. Buoyancy.  After every substep any density inversion (a layer warmer than the one above it) is
   removed at once by merging the inverted layers into their common mean (pool-adjacent-violators,
   merged until stable), which conserves the energy exactly.  Water is assumed above 4 degC, so
   "warmer" means "lighter".  The original relaxes inversions with a ~1 s lagged mixing flow and
   wipes them out within tens of seconds; instantaneous merging is the limit of that at
   1 s ... 60 s steps.
3. Conduction between neighbouring layers: UA_layer * (T_k - T_k+1) per interface, explicit.
   Default (UA_layer < 0): still water, 0.6 W/(m K) * A / dz, independent of the layer count in
   effect (7.2 W/K per interface for the 800 l tank at 40 layers).  The original used
   alpha * A = 0.49 W/K per interface at 10 layers (an effective conductivity of 0.16 W/(m K)).
4. Losses UA_loss * (T_k - T_env) / N from every layer (spread equally over the layers, as the
   original does; no extra top/bottom weighting).
5. Coils (internal heat exchangers).  A coil carries fluid from its inlet layer coil_top to its
   outlet layer coil_bot (downward; upward when coil_top lies below, as fresh water rises through a
   DHW coil); it is modelled as one segment per spanned layer in series,
   each an exact steady-state exchanger against its layer:
       eps = 1 - exp(-UA_seg / (m CP)),  UA_seg = coil_UA / n_seg,
       Q_seg = m CP eps (theta_in - T_layer),  theta_out = theta_in - eps (theta_in - T_layer),
   so the heat given to the tank equals m CP (T_in - T_out) exactly.  The coil fluid holds no
   energy (the original's 6-12 l coil volume lag is dropped).

All flows are explicit within a substep; the number of substeps is chosen so that per layer
    dt_sub * [ (mass leaving the layer per s) / m_layer + (2 UA_layer + UA_loss/N + sum_c g_c) / C_layer ]
    <= 0.5       (g_c = eps_c m_c CP, the largest conductance a coil segment can have)
which keeps the Courant number <= 0.5 and the conduction/coil coupling stable.  A 1 s step of the
800 l tank at 40 layers needs 1 substep up to ~600 l/min; a 60 s step needs 1 substep up to
~9 l/min, 2 at 10 l/min.  `n_substeps` returns the count the kernel will use.

Energy ledger: CP * m_layer * sum(T_new - T_old) == dt * (sum in_m CP in_T - sum out_m CP out_T
- Q_loss + Q_coil) to round-off (the face fluxes telescope), where out_T, Q_loss and Q_coil are the
step means returned/filled by the kernel (out_T is the enthalpy-weighted outflow temperature over
the substeps, i.e. the time mean of its layer temperature since out_m is constant in a step).

Parameters (`Params`, packed in field order; indices I_*)
----------------------------------------------------------
| name          | default | unit   | range       | meaning                                         |
|---------------|---------|--------|-------------|-------------------------------------------------|
| volume        | 0.8     | m3     | 0.01..100   | water volume                                    |
| height        | 1.63    | m      | 0.1..20     | equivalent height V/A (A = cross-section)       |
| n_layers      | 40      | 1      | 3..200      | number of equal layers (must equal len(T))      |
| UA_loss       | 20.0    | W/K    | 0..1000     | total loss to ambient (house 1 buffer 20, DHW 7)|
| T_env         | 18.0    | degC   | -30..60     | ambient temperature of the losses               |
| UA_layer      | -1.0    | W/K    | -1..1e5     | conductance per interface; < 0: 0.6 W/(m K)A/dz |
| limiter       | 3       | 1      | 0..3        | 0 upwind, 1 van Leer, 2 MC, 3 superbee          |
| T_init_top    | 80.0    | degC   | 0..100      | initial top layer (linear profile)              |
| T_init_bottom | 40.0    | degC   | 0..100      | initial bottom layer                            |
| soc_T0        | 40.0    | degC   | 0..100      | mean temperature of SOC 0 and of E_stored = 0   |
| soc_Tmax      | 80.0    | degC   | 1..120      | mean temperature of SOC 1                       |

House 1 values: buffer "WolfSPU2_800" 0.80 m3, 1.63 m, UA 20 W/K; DHW tank "WolfSEM1_500"
0.50 m3, 1.51 m, UA 7 W/K, initial 65 -> 40 degC.  Coil parameters are per call (arrays):
DHW charging coil 0.95 m2 * 675 W/(m2 K) = 641 W/K over the original layers 8..6 (of 10, counted
from the bottom), solar coil 1.8 m2 * 675 = 1215 W/K over layers 5..1; use `port_layer` to map
heights to layer indices at any N.

State of charge, stored energy and sensor temperatures read off the layers (`soc`, `SOC_BUFFER`,
`SOC_DHW`, `stored_energy`, `sensor_temperatures`): plant/components/storage_readings.py.

Assumptions
-----------
* Every direct inflow mixes completely into its layer (no plume, no stratifying lance).
* Water above 4 degC (buoyancy by temperature order); constant CP = 4180 J/(kg K), RHO = 1000 kg/m3
  for masses (plant/water.py); the layer mass is RHO V / N.
* The caller guarantees sum(in_m) == sum(out_m) within round-off; the energy ledger is exact
  regardless, but a mass imbalance would be absorbed by the bottom layer's temperature.
* Coil fluid has no storage; a coil with zero flow exchanges no heat and reports the temperature
  of its last layer as outlet.

Measured numerical front (test_hot_charge_front_stays_sharp): 800 l, 1.63 m, 40 layers
(dz = 4.1 cm), 20 degC tank, 70 degC in at the top at 10 l/min, out at the bottom, dt = 1 s,
default still-water conduction; after the front has travelled half the tank (2400 s) the
10-90 % width is 3.2 layers = 0.13 m with superbee (MC: 4.5 layers = 0.18 m; first-order upwind,
the original's scheme: 11.5 layers = 0.47 m, as predicted by D_num = u dz/2).  About 2.2 layers of
this is the inlet layer's exponential fill (20 kg at 10 l/min, time constant 120 s) and 1.6 layers
is the still-water conduction.  At dt = 60 s (2 substeps, Courant 0.25) the width is 2.9 layers;
the same for a cold front rising from the bottom (discharge).

Cost: ~1.0 us per 1 s step for 40 layers, 2 inflows, 2 outflows, 1 coil, 1 substep, called from a
compiled loop (0.9 us with the upwind scheme); about 3 us when called from Python.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from ..component import indices, param
from ..water import CP, RHO
from .storage_flows import flowing, next_port_layer, port_layer, worst_outflow

K_WATER = 0.6  # W/(m K), still-water conductivity used for the default UA_layer
COURANT_MAX = 0.5  # per-substep bound on (outflow Courant number + conduction/coil number)

LIMITER_UPWIND, LIMITER_VANLEER, LIMITER_MC, LIMITER_SUPERBEE = 0, 1, 2, 3


@dataclass(frozen=True)
class Params:
    volume: float = param(0.8, "m3", "water volume", 0.01, 100.0)
    height: float = param(1.63, "m", "equivalent height V/A", 0.1, 20.0)
    n_layers: int = param(40, "1", "number of equal-volume layers (layer 0 = top)", 3, 200)
    UA_loss: float = param(20.0, "W/K", "heat-loss coefficient to ambient, spread equally over layers", 0.0, 1000.0)
    T_env: float = param(18.0, "degC", "ambient temperature for the losses", -30.0, 60.0)
    UA_layer: float = param(
        -1.0, "W/K", "conductance per layer interface; negative = still water 0.6 W/(m K)*A/dz", -1.0, 1e5
    )
    limiter: int = param(LIMITER_SUPERBEE, "1", "advection: 0 upwind, 1 van Leer, 2 MC, 3 superbee", 0, 3)
    T_init_top: float = param(80.0, "degC", "initial temperature of the top layer", 0.0, 100.0)
    T_init_bottom: float = param(40.0, "degC", "initial temperature of the bottom layer", 0.0, 100.0)
    soc_T0: float = param(40.0, "degC", "mean temperature of SOC 0 and of zero stored heat (E_stored)", 0.0, 100.0)
    soc_Tmax: float = param(80.0, "degC", "mean temperature of SOC 1", 1.0, 120.0)


# positions in the packed parameter vector, from the declaration
P = indices(Params)


def state_names(params: Params) -> list[str]:
    """Names of the state entries: layer temperatures, top first."""
    return [f"T_layer{k}" for k in range(params.n_layers)]


def initial_state(params: Params) -> np.ndarray:
    """Layer temperatures [degC], linear from T_init_top (layer 0) to T_init_bottom (layer N-1)."""
    return np.linspace(params.T_init_top, params.T_init_bottom, params.n_layers).astype(np.float64)


def layer_conductance(params: Params) -> float:
    """Effective conductance per interface [W/K] the kernel uses (resolves UA_layer < 0)."""
    if params.UA_layer >= 0.0:
        return float(params.UA_layer)
    return K_WATER * params.volume * params.n_layers / params.height**2


# ----------------------------------------------------------------------------------------------
# kernel


@njit(cache=True, inline="always")
def _ua_layer(p, N):
    ua = p[P.UA_layer]
    if ua < 0.0:
        ua = K_WATER * p[P.volume] * N / (p[P.height] * p[P.height])
    return ua


@njit(cache=True, inline="always")
def _limiter(r, kind):
    if kind == 2:  # MC
        a = 2.0 * r
        b = 0.5 * (1.0 + r)
        m = a if a < b else b
        if m > 2.0:
            m = 2.0
        return m if m > 0.0 else 0.0
    if kind == 1:  # van Leer
        ar = abs(r)
        return (r + ar) / (1.0 + ar)
    if kind == 3:  # superbee
        a = 2.0 * r
        if a > 1.0:
            a = 1.0
        b = r if r < 2.0 else 2.0
        m = a if a > b else b
        return m if m > 0.0 else 0.0
    return 0.0


@njit(cache=True)
def n_substeps(dt, T, p, in_layer, in_m, out_layer, out_m, coil_UA, coil_m, coil_top, coil_bot):
    """Number of equal substeps `step` uses for this dt and these flows (>= 1)."""
    N = T.shape[0]
    mL = RHO * p[P.volume] / N
    C = CP * mL
    ua = _ua_layer(p, N)
    g = 0.0
    for c in range(coil_UA.shape[0]):
        m = coil_m[c]
        if m > 0.0 and coil_UA[c] > 0.0:
            nseg = abs(coil_bot[c] - coil_top[c]) + 1
            eps = 1.0 - math.exp(-coil_UA[c] / nseg / (m * CP))
            g += eps * m * CP
    rate = worst_outflow(N, in_layer, in_m, out_layer, out_m) / mL + (2.0 * ua + p[P.UA_loss] / N + g) / C
    x = dt * rate / COURANT_MAX
    n = int(math.ceil(x))
    return n if n >= 1 else 1


@njit(cache=True, inline="always")
def _remove_inversions(T):
    """Merge inverted layers (warmer below colder) into their mean until stable; energy exact."""
    N = T.shape[0]
    for k in range(1, N):
        if T[k] > T[k - 1]:
            s = T[k] + T[k - 1]
            cnt = 2
            j = k - 2
            mean = 0.5 * s
            while j >= 0 and T[j] < mean:
                s += T[j]
                cnt += 1
                j -= 1
                mean = s / cnt
            for i in range(j + 1, k + 1):
                T[i] = mean


@njit(cache=True, inline="always")
def _losses_and_ports(T, q_layer, uaN, Tenv, in_layer, in_m, in_T, out_layer, out_m, out_T, Q_loss):
    """Sources into q_layer [W]: losses and port enthalpy; adds each outflow's layer temperature
    to out_T. Returns Q_loss plus this substep's loss."""
    N = T.shape[0]
    sT = 0.0
    for k in range(N):
        sT += T[k]
        q_layer[k] = -uaN * (T[k] - Tenv)
    Q_loss += uaN * (sT - N * Tenv)
    for i in range(in_layer.shape[0]):
        q_layer[in_layer[i]] += in_m[i] * CP * in_T[i]
    for j in range(out_layer.shape[0]):
        Tk = T[out_layer[j]]
        out_T[j] += Tk
        q_layer[out_layer[j]] -= out_m[j] * CP * Tk
    return Q_loss


@njit(cache=True, inline="always")
def _coils(T, q_layer, coil_top, coil_bot, coil_UA, coil_m, coil_Tin, coil_Tout, Q_coil):
    """Coil heat into q_layer, segment by segment from the inlet layer; adds each coil's outlet
    temperature to coil_Tout. Returns Q_coil plus this substep's coil heat."""
    for c in range(coil_top.shape[0]):
        m = coil_m[c]
        top = coil_top[c]
        bot = coil_bot[c]
        if m > 0.0 and coil_UA[c] > 0.0:
            nseg = abs(bot - top) + 1
            eps = 1.0 - math.exp(-coil_UA[c] / nseg / (m * CP))
            mc = m * CP
            th = coil_Tin[c]
            way = 1 if bot >= top else -1  # coil_top is the inlet layer: below the outlet = upward
            for k in range(top, bot + way, way):
                dth = eps * (th - T[k])
                q_layer[k] += mc * dth
                th -= dth
            Q_coil += mc * (coil_Tin[c] - th)
            coil_Tout[c] += th
        else:
            coil_Tout[c] += T[bot]
    return Q_coil


@njit(cache=True, inline="always")
def _interfaces(T, q_layer, ua, kind, hm, in_layer, in_m, out_layer, out_m):
    """Advective (flux-limited) + conductive enthalpy flow downward across every face, into
    q_layer."""
    N = T.shape[0]
    F = 0.0
    nxt = next_port_layer(-1, N, in_layer, out_layer)
    for k in range(N - 1):
        if k == nxt:  # only a port layer changes the flow its faces carry
            for i in range(in_layer.shape[0]):
                if in_layer[i] == k:
                    F += in_m[i]
            for j in range(out_layer.shape[0]):
                if out_layer[j] == k:
                    F -= out_m[j]
            nxt = next_port_layer(k, N, in_layer, out_layer)
        flux = ua * (T[k] - T[k + 1])
        if F > 0.0:
            TU = T[k]
            d = T[k + 1] - TU
            Tf = TU
            if kind != 0 and k >= 1 and d != 0.0:
                phi = _limiter((TU - T[k - 1]) / d, kind)
                Tf = TU + 0.5 * phi * (1.0 - F * hm) * d
            flux += F * CP * Tf
        elif F < 0.0:
            TU = T[k + 1]
            d = T[k] - TU
            Tf = TU
            if kind != 0 and k + 2 < N and d != 0.0:
                phi = _limiter((TU - T[k + 2]) / d, kind)
                Tf = TU + 0.5 * phi * (1.0 + F * hm) * d
            flux += F * CP * Tf
        q_layer[k] -= flux
        q_layer[k + 1] += flux


@njit(cache=True)
def step(dt, T, p, in_layer, in_m, in_T, out_layer, out_m, out_T,
         coil_top, coil_bot, coil_UA, coil_m, coil_Tin, coil_Tout, q_layer):
    """Advance the layer temperatures T (top first, in place) by dt [s].

    Fills out_T (mean temperature of each outflow over the step) and coil_Tout (mean coil outlet
    temperature); q_layer (len N) is scratch.  Returns (Q_loss, Q_coil) [W], step means: heat lost
    to ambient and heat given by the coils to the tank. (step_into with its port scratch
    allocated here; the compiled plant allocates it once and calls step_into.)
    """
    nin, nout = in_layer.shape[0], out_layer.shape[0]
    return step_into(dt, T, p, in_layer, in_m, in_T, out_layer, out_m, out_T, coil_top, coil_bot, coil_UA, coil_m,
                     coil_Tin, coil_Tout, q_layer, np.empty(nin, np.int64), np.empty(nin),
                     np.empty(nout, np.int64), np.empty(nout))


@njit(cache=True)
def step_into(dt, T, p, in_layer, in_m, in_T, out_layer, out_m, out_T,
              coil_top, coil_bot, coil_UA, coil_m, coil_Tin, coil_Tout, q_layer,
              fin_layer, fin_m, fout_layer, fout_m):
    """step, with the flowing ports' scratch (fin_*: the inflows' length, fout_*: the outflows')."""
    N = T.shape[0]
    mL = RHO * p[P.volume] / N
    C = CP * mL
    ua = _ua_layer(p, N)
    uaN = p[P.UA_loss] / N
    Tenv = p[P.T_env]
    kind = int(p[P.limiter])
    nout = out_layer.shape[0]
    ncoil = coil_top.shape[0]

    # the advection's ports: the idle ones add nothing
    k_in = flowing(in_layer, in_m, fin_layer, fin_m)
    k_out = flowing(out_layer, out_m, fout_layer, fout_m)
    fin_layer, fin_m, fout_layer, fout_m = fin_layer[:k_in], fin_m[:k_in], fout_layer[:k_out], fout_m[:k_out]
    nsub = n_substeps(dt, T, p, fin_layer, fin_m, fout_layer, fout_m, coil_UA, coil_m, coil_top, coil_bot)
    h = dt / nsub
    hm = h / mL  # converts a mass flow into a Courant number
    hC = h / C

    for j in range(nout):
        out_T[j] = 0.0
    for c in range(ncoil):
        coil_Tout[c] = 0.0
    Q_loss = 0.0
    Q_coil = 0.0

    for _s in range(nsub):
        Q_loss = _losses_and_ports(T, q_layer, uaN, Tenv, in_layer, in_m, in_T, out_layer, out_m, out_T, Q_loss)
        Q_coil = _coils(T, q_layer, coil_top, coil_bot, coil_UA, coil_m, coil_Tin, coil_Tout, Q_coil)
        _interfaces(T, q_layer, ua, kind, hm, fin_layer, fin_m, fout_layer, fout_m)
        for k in range(N):
            T[k] += q_layer[k] * hC
        _remove_inversions(T)

    inv = 1.0 / nsub
    for j in range(nout):
        out_T[j] *= inv
    for c in range(ncoil):
        coil_Tout[c] *= inv
    return Q_loss * inv, Q_coil * inv


__all__ = [
    "Params", "initial_state", "state_names", "layer_conductance", "step", "n_substeps", "port_layer",
    "P",
]
