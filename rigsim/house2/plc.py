"""The lab PLC's rules for rigsim's house-2 rig (rig description section 4)."""
from __future__ import annotations

from numba import njit

from .layout import (
    F_HC_FSET, F_HC_I, F_SOL_SET, I_AUX_CMD, I_BOI_CMD, I_HP_CMD, I_SOL_CMD, I_SOL_WAS_ON, I_VALVE,
    PR_COLL, PR_ROOM, PR_ST_RL, P_T_DAY, P_T_NIGHT,
)


@njit(cache=True)
def _hyst(state, on_cond, off_cond):
    if off_cond:
        return 0
    if on_cond:
        return 1
    return state


@njit(cache=True)
def plc(P, ist, fst, sb, pr, hour, dt):
    """The lab PLC's rules (rig description section 4), in their order, once a second."""
    up = ist[I_VALVE]
    up = _hyst(up, sb[7] < 55.0, sb[6] > 60.0)
    ist[I_VALVE] = up
    hp = _hyst(ist[I_HP_CMD], up == 1 or sb[2] < 43.0, up == 0 and sb[1] > 45.0)
    ist[I_HP_CMD] = hp
    ist[I_AUX_CMD] = _hyst(ist[I_AUX_CMD], hp == 1 and (sb[7] < 50.0 or sb[2] < 35.0),
                           hp == 0 or ((sb[6] > 55.0 or up == 0) and sb[1] > 40.0))
    ist[I_BOI_CMD] = _hyst(ist[I_BOI_CMD], sb[9] < 55.0 or sb[4] < 35.0, sb[4] > 60.0)
    dT = pr[PR_COLL] - sb[4]
    ist[I_SOL_CMD] = _hyst(ist[I_SOL_CMD], dT > 3.0, dT < 2.0 or sb[4] > 95.0)
    if ist[I_SOL_CMD] == 1:
        T_ret = pr[PR_ST_RL] if ist[I_SOL_WAS_ON] == 1 else sb[4]
        fst[F_SOL_SET] = min(20.0, max(0.0, 20.0 * (pr[PR_COLL] - T_ret - 3.0) / 4.0))
    else:
        fst[F_SOL_SET] = 0.0
    ist[I_SOL_WAS_ON] = 1 if (ist[I_SOL_CMD] == 1 and fst[F_SOL_SET] > 0.0) else 0
    # room thermostat (PI, clamped, integration stops at a limit when e pushes beyond)
    T_set = P[P_T_NIGHT] if (hour >= 23.0 or hour < 7.0) else P[P_T_DAY]
    e = T_set - pr[PR_ROOM]
    out = e + fst[F_HC_I] / 1800.0
    if not ((out >= 1.0 and e > 0.0) or (out <= 0.0 and e < 0.0)):
        fst[F_HC_I] += e * dt
        out = e + fst[F_HC_I] / 1800.0
    fst[F_HC_FSET] = 15.0 * min(1.0, max(0.0, out))
