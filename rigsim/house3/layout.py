"""Where everything lives in the flat arrays of rigsim's house-3 core.

House 3's layout *extends* house 2's (rigsim/house2/layout.py): the parameter vector, the lumped
nodes, the probes and the controller states keep house 2's names at house 2's indices and append
house 3's own, so that house 2's PLC, three-way valve, mixing station, heating circuit and chain
kernels (numba functions that index these arrays by house 2's constants) run on house 3's arrays
unchanged. House 2's boiler slots stay unused (zero capacity, never advanced). The ledger, the
channels and the aux record are house 3's own.
"""
from ..house2 import layout as _h2

CP = _h2.CP


def _append(base: list, more: str) -> tuple[list, range]:
    names = list(base) + more.split()
    return names, range(len(base), len(names))


# ---- parameter vector P: house 2's 51, then house 3's -------------------------------------
P_NAMES, _r = _append(_h2.P_NAMES, """HP_TSTART BR_M BR_CPF BR_UA SOIL_C SOIL_UA BR_PIPE_UA
SOL_UA_SEG_LO""")
P_HP_TSTART, P_BR_M, P_BR_CPF, P_BR_UA, P_SOIL_C, P_SOIL_UA, P_BR_PIPE_UA, P_SOL_UA_SEG_LO = _r
N_PARAM = len(P_NAMES)
(P_DT, P_T_PLANT, P_T_COLD, P_M_CELL, P_KCOND, P_HP_UA, P_HP_SPREAD, P_HP_QNOM, P_HP_PNOM,
 P_HP_CAPF, P_HP_AUX_W, P_HPP_UA, P_COL_A, P_COL_ETA0, P_COL_A1, P_COL_A2, P_SOL_PIPE_UA,
 P_SOL_PUMP_F, P_SOL_UA_SEG, P_SOL_C_SEG, P_PV_KWP, P_HC_TSET, P_B_NPERS, P_B_WPERS, P_TAU_PROBE,
 P_TAU_ROOM, P_TAU_COLL, P_T_DHW) = (
    _h2.P_DT, _h2.P_T_PLANT, _h2.P_T_COLD, _h2.P_M_CELL, _h2.P_KCOND, _h2.P_HP_UA,
    _h2.P_HP_SPREAD, _h2.P_HP_QNOM, _h2.P_HP_PNOM, _h2.P_HP_CAPF, _h2.P_HP_AUX_W, _h2.P_HPP_UA,
    _h2.P_COL_A, _h2.P_COL_ETA0, _h2.P_COL_A1, _h2.P_COL_A2, _h2.P_SOL_PIPE_UA, _h2.P_SOL_PUMP_F,
    _h2.P_SOL_UA_SEG, _h2.P_SOL_C_SEG, _h2.P_PV_KWP, _h2.P_HC_TSET, _h2.P_B_NPERS,
    _h2.P_B_WPERS, _h2.P_TAU_PROBE, _h2.P_TAU_ROOM, _h2.P_TAU_COLL, _h2.P_T_DHW)

# ---- sensor pipe-water nodes (s-arrays): house 2's boiler pair is house 3's brine pair -----
S_HP_VL, S_HP_RL, S_BR_IN, S_BR_OUT, S_HC_VL, S_HC_RL = range(6)

# ---- lumped nodes: house 2's 20, then the brine loop ----------------------------------------
N_NAMES, _r = _append(_h2.N_NAMES, "BR_SUP BR_IN EVAP BR_OUT BR_RET")
N_BR_SUP, N_BR_IN, N_EVAP, N_BR_OUT, N_BR_RET = _r
N_NODES = len(N_NAMES)
N_H2 = _h2.N_NODES          # house 2's stored_heat sums the first N_H2 nodes
(N_HP, N_HPR_PIPE, N_HPS_PIPE, N_HP_VL, N_HP_RL, N_HCS, N_HCR, N_HC_VL, N_HC_RL, N_COL, N_SPS,
 N_SPR, N_SLAB, N_ROOM, N_MASS) = (
    _h2.N_HP, _h2.N_HPR_PIPE, _h2.N_HPS_PIPE, _h2.N_HP_VL, _h2.N_HP_RL, _h2.N_HCS, _h2.N_HCR,
    _h2.N_HC_VL, _h2.N_HC_RL, _h2.N_COL, _h2.N_SPS, _h2.N_SPR, _h2.N_SLAB, _h2.N_ROOM, _h2.N_MASS)

# ---- probes: house 2's 13 (boiler and switch probes unused), then the brine pair -------------
PR_NAMES, _r = _append(_h2.PR_NAMES, "BR_IN BR_OUT")
PR_BR_IN, PR_BR_OUT = _r
N_PROBE = len(PR_NAMES)
(PR_HP_VL, PR_HP_RL, PR_HC_HDR, PR_HC_VL, PR_HC_RL, PR_ST_VL, PR_ST_RL, PR_COLL, PR_ROOM) = (
    _h2.PR_HP_VL, _h2.PR_HP_RL, _h2.PR_HC_HDR, _h2.PR_HC_VL, _h2.PR_HC_RL, _h2.PR_ST_VL,
    _h2.PR_ST_RL, _h2.PR_COLL, _h2.PR_ROOM)

# ---- controller / unit states: house 2's, then the solar valve and the soil -----------------
IS_NAMES, _r = _append(_h2.IS_NAMES, "SOLV")
(I_SOLV,) = _r
N_IS = len(IS_NAMES)
I_VALVE, I_HP_CMD, I_AUX_CMD, I_SOL_CMD, I_HP_RUN = (
    _h2.I_VALVE, _h2.I_HP_CMD, _h2.I_AUX_CMD, _h2.I_SOL_CMD, _h2.I_HP_RUN)
FS_NAMES, _r = _append(_h2.FS_NAMES, "SOIL")
(F_SOIL,) = _r
N_FS = len(FS_NAMES)
F_HP_TON, F_SOL_SET, F_HC_FSET, F_VALVE_X = (_h2.F_HP_TON, _h2.F_SOL_SET, _h2.F_HC_FSET,
                                            _h2.F_VALVE_X)

# ---- ledger (house 3's own) ------------------------------------------------------------------
L_NAMES = """EL GROUND SOLABS GENLOSS COLLOSS PIPELOSS STORELOSS BUILDING DHW E0 E1 HP_RUN HP_HEAT
HP_ELC EVAP SOL_HEAT SOL_RUN SOL_UP SOL_LEAK_MASS TMIN TMAX BRIN_SUM HEAT_T SOIL_END""".split()
(L_EL, L_GROUND, L_SOLABS, L_GENLOSS, L_COLLOSS, L_PIPELOSS, L_STORELOSS, L_BUILDING, L_DHW,
 L_E0, L_E1, L_HP_RUN, L_HP_HEAT, L_HP_ELC, L_EVAP, L_SOL_HEAT, L_SOL_RUN, L_SOL_UP,
 L_SOL_LEAK_MASS, L_TMIN, L_TMAX, L_BRIN_SUM, L_HEAT_T, L_SOIL_END) = range(len(L_NAMES))
N_LEDGER = len(L_NAMES)

# ---- channels, in the order of docs/lab/house3-channels.csv (checked by rigsim.house3.daq) ---
CH_NAMES = """GSHP_GSHP_on GSHP_AuxModulation_set GSHP_A_V3_TL ST_PUMP_CMD ST_S_FW_ST_VL_set
ST_A_V3_TL STM_HCVLaM_Set_degC SFW_HCRLbM_Set_l_per_min S_TM_ambient DirectRadiation_W_per_m2
DiffuseRadiation_W_per_m2 T_ground_degC TS_S_TM_BT_1 TS_S_TM_BT_2 TS_S_TM_BT_3 TS_S_TM_BT_4
TS_S_TM_BT_5 TS_S_TM_BT_6 TS_S_TM_BT_7 TS_S_TM_BT_8 TS_S_TM_BT_9 TS_S_TM_BT_10 HP_S_TM_VL
HP_S_TM_RL HP_S_FW_HC HP_P_heat_Tot HP_P_elec_is HP_COP HP_S_TM_BC_VL HP_S_TM_BC_RL HP_S_FW_BC
ST_S_TM_COLL ST_S_TM_VL ST_S_TM_RL ST_S_FW_ST_VL ST_P_heat PV_P_gen P_elConsumption_kW
STM_HCVLbM_degC STM_HCVLaM_degC STM_HCRL_degC SFW_HCRLbM_l_per_min SFW_HCVLbM_l_per_min
HS_S_FW_HW S_TM_room""".split()
N_CH = len(CH_NAMES)
CH = {name: i for i, name in enumerate(CH_NAMES)}
C_BT0 = CH["TS_S_TM_BT_1"]
# channels that log a probe as it reads (the core copies pr[probe] into ch[channel])
PROBE_CHANNELS = {"HP_S_TM_VL": PR_HP_VL, "HP_S_TM_RL": PR_HP_RL, "HP_S_TM_BC_VL": PR_BR_IN,
                  "HP_S_TM_BC_RL": PR_BR_OUT, "ST_S_TM_COLL": PR_COLL, "ST_S_TM_VL": PR_ST_VL,
                  "ST_S_TM_RL": PR_ST_RL, "STM_HCVLbM_degC": PR_HC_HDR,
                  "STM_HCVLaM_degC": PR_HC_VL, "STM_HCRL_degC": PR_HC_RL, "S_TM_room": PR_ROOM}

# ---- aux record per sample ---------------------------------------------------------------------
A_VALVE, A_HP_STATE, A_M_HP, A_M_SOL, A_SOLV_X, A_Q_EVAP, A_T_SOIL, A_M_PRIM = range(8)
N_AUX = 8
