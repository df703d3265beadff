"""Where everything lives in the flat arrays rigsim's house-2 core works on: the parameter vector
``P`` (filled by rigsim.house2.model.simulate), the sensor pipe-water nodes, the lumped nodes, the
ledger, the channels, the probes, the aux record and the controller / unit states."""

CP = 4180.0

# ---- parameter vector P -------------------------------------------------------------------
_P = """DT T_PLANT T_COLD M_CELL KCOND HP_UA HP_SPREAD HP_QNOM HP_PNOM HP_CAPF HP_DEFROST_S HP_MMIN_FLOW
HP_MMAX_FLOW HP_AUX_W HPP_UA VALVE_T LEAK BOI_UA BOI_DTSET BOI_ETAF HDR_UA COL_A COL_ETA0 COL_A1
COL_A2 SOL_PIPE_UA SOL_PUMP_F SOL_UA_SEG SOL_C_SEG PV_KWP HC_PUMP_MAX HC_T_RUN HC_TSET HC_KI
FL_C_SEG FL_UA_SEG FL_K FL_N B_CR B_CM B_HRM B_HRO B_HMO B_NPERS B_WPERS T_DAY T_NIGHT TAU_PROBE
TAU_ROOM TAU_COLL T_DHW"""
P_NAMES = _P.split()
(
    P_DT, P_T_PLANT, P_T_COLD, P_M_CELL, P_KCOND, P_HP_UA, P_HP_SPREAD, P_HP_QNOM, P_HP_PNOM,
    P_HP_CAPF, P_HP_DEFROST_S, P_HP_MMIN_FLOW, P_HP_MMAX_FLOW, P_HP_AUX_W, P_HPP_UA, P_VALVE_T,
    P_LEAK, P_BOI_UA, P_BOI_DTSET, P_BOI_ETAF, P_HDR_UA, P_COL_A, P_COL_ETA0, P_COL_A1,
    P_COL_A2, P_SOL_PIPE_UA, P_SOL_PUMP_F, P_SOL_UA_SEG, P_SOL_C_SEG, P_PV_KWP, P_HC_PUMP_MAX,
    P_HC_T_RUN, P_HC_TSET, P_HC_KI, P_FL_C_SEG, P_FL_UA_SEG, P_FL_K, P_FL_N, P_B_CR, P_B_CM,
    P_B_HRM, P_B_HRO, P_B_HMO, P_B_NPERS, P_B_WPERS, P_T_DAY, P_T_NIGHT, P_TAU_PROBE,
    P_TAU_ROOM, P_TAU_COLL, P_T_DHW,
) = range(51)
N_PARAM = 51

# sensor pipe-water nodes (index into the s-arrays)
S_HP_VL, S_HP_RL, S_CB_VL, S_CB_RL, S_HC_VL, S_HC_RL = range(6)

# lumped node temperatures: nodes[]
_N = """HP HPR_PIPE HPS_PIPE HP_VL HP_RL BOI CB_VL CB_RL SH RH HCS HCR HC_VL HC_RL COL SPS SPR SLAB
ROOM MASS"""
N_NAMES = _N.split()
(
    N_HP, N_HPR_PIPE, N_HPS_PIPE, N_HP_VL, N_HP_RL, N_BOI, N_CB_VL, N_CB_RL, N_SH, N_RH, N_HCS,
    N_HCR, N_HC_VL, N_HC_RL, N_COL, N_SPS, N_SPR, N_SLAB, N_ROOM, N_MASS,
) = range(20)
N_NODES = 20

# ledger
_L = """GAS EL AMB SOLABS GENLOSS COLLOSS PIPELOSS STORELOSS BUILDING DHW E0 E1
HP_RUN DEFROST HP_HEAT HP_ELC SOL_HEAT SOL_RUN LEAK_MASS TMIN TMAX"""
L_NAMES = _L.split()
(
    L_GAS, L_EL, L_AMB, L_SOLABS, L_GENLOSS, L_COLLOSS, L_PIPELOSS, L_STORELOSS, L_BUILDING,
    L_DHW, L_E0, L_E1, L_HP_RUN, L_DEFROST, L_HP_HEAT, L_HP_ELC, L_SOL_HEAT, L_SOL_RUN,
    L_LEAK_MASS, L_TMIN, L_TMAX,
) = range(21)
N_LEDGER = 21

# channels, in the order of docs/lab/house2-channels.csv (checked by rigsim.house2.daq)
CH_NAMES = """ASHP_ASHP_on ASHP_Modulation_set ASHP_AuxModulation_set ASHP_A_V3_TL EB_EB_power_kW_set
ST_PUMP_CMD ST_S_FW_ST_VL_set STM_HCVLaM_Set_degC SFW_HCRLbM_Set_l_per_min S_TM_ambient
DirectRadiation_W_per_m2 DiffuseRadiation_W_per_m2 TS_S_TM_BT_1 TS_S_TM_BT_2 TS_S_TM_BT_3
TS_S_TM_BT_4 TS_S_TM_BT_5 TS_S_TM_BT_6 TS_S_TM_BT_7 TS_S_TM_BT_8 TS_S_TM_BT_9 TS_S_TM_BT_10
HP_S_TM_VL HP_S_TM_RL HP_S_FW_HC HP_P_heat_Tot HP_P_elec_is HP_COP CB_S_TM_VL CB_S_TM_RL CB_S_FW
CB_P_heat CB_P_gas TS_S_TM_PS_VL TS_S_TM_PS_RL ST_S_TM_COLL ST_S_TM_VL ST_S_TM_RL ST_S_FW_ST_VL
ST_P_heat PV_P_gen P_elConsumption_kW STM_HCVLbM_degC STM_HCVLaM_degC STM_HCRL_degC
SFW_HCRLbM_l_per_min SFW_HCVLbM_l_per_min HS_S_FW_HW S_TM_room""".split()
N_CH = len(CH_NAMES)
C_BT0 = CH_NAMES.index("TS_S_TM_BT_1")
(
    C_ASHP_ASHP_on, C_ASHP_Modulation_set, C_ASHP_AuxModulation_set, C_ASHP_A_V3_TL,
    C_EB_EB_power_kW_set, C_ST_PUMP_CMD, C_ST_S_FW_ST_VL_set, C_STM_HCVLaM_Set_degC,
    C_SFW_HCRLbM_Set_l_per_min, C_S_TM_ambient, C_DirectRadiation_W_per_m2,
    C_DiffuseRadiation_W_per_m2, C_TS_S_TM_BT_1, C_TS_S_TM_BT_2, C_TS_S_TM_BT_3, C_TS_S_TM_BT_4,
    C_TS_S_TM_BT_5, C_TS_S_TM_BT_6, C_TS_S_TM_BT_7, C_TS_S_TM_BT_8, C_TS_S_TM_BT_9,
    C_TS_S_TM_BT_10, C_HP_S_TM_VL, C_HP_S_TM_RL, C_HP_S_FW_HC, C_HP_P_heat_Tot, C_HP_P_elec_is,
    C_HP_COP, C_CB_S_TM_VL, C_CB_S_TM_RL, C_CB_S_FW, C_CB_P_heat, C_CB_P_gas, C_TS_S_TM_PS_VL,
    C_TS_S_TM_PS_RL, C_ST_S_TM_COLL, C_ST_S_TM_VL, C_ST_S_TM_RL, C_ST_S_FW_ST_VL, C_ST_P_heat,
    C_PV_P_gen, C_P_elConsumption_kW, C_STM_HCVLbM_degC, C_STM_HCVLaM_degC, C_STM_HCRL_degC,
    C_SFW_HCRLbM_l_per_min, C_SFW_HCVLbM_l_per_min, C_HS_S_FW_HW, C_S_TM_room,
) = range(49)

# probes (first-order thermowell / sensor lags)
_PR = "HP_VL HP_RL CB_VL CB_RL PS_VL PS_RL HC_HDR HC_VL HC_RL ST_VL ST_RL COLL ROOM"
PR_NAMES = _PR.split()
(
    PR_HP_VL, PR_HP_RL, PR_CB_VL, PR_CB_RL, PR_PS_VL, PR_PS_RL, PR_HC_HDR, PR_HC_VL, PR_HC_RL,
    PR_ST_VL, PR_ST_RL, PR_COLL, PR_ROOM,
) = range(13)
N_PROBE = 13

# aux record per sample
A_VALVE, A_HP_STATE, A_BOI_STATE, A_M_HP, A_M_SOL, A_Q_SLAB, A_M_PRIM, A_SHARE_UP = range(8)
N_AUX = 8

# integer / float controller and unit states
_IS = "VALVE HP_CMD AUX_CMD BOI_CMD SOL_CMD HP_RUN HP_DEFR BOI_RUN BOI_LOCK SOL_WAS_ON"
IS_NAMES = _IS.split()
(
    I_VALVE, I_HP_CMD, I_AUX_CMD, I_BOI_CMD, I_SOL_CMD, I_HP_RUN, I_HP_DEFR, I_BOI_RUN,
    I_BOI_LOCK, I_SOL_WAS_ON,
) = range(10)
N_IS = 10
_FS = "HP_TON HP_Y BOI_TON BOI_TOFF BOI_Y BOI_MSTOP BOI_M SOL_SET HC_FSET HC_I VALVE_X U U_I HP_PREV_M"
FS_NAMES = _FS.split()
(
    F_HP_TON, F_HP_Y, F_BOI_TON, F_BOI_TOFF, F_BOI_Y, F_BOI_MSTOP, F_BOI_M, F_SOL_SET,
    F_HC_FSET, F_HC_I, F_VALVE_X, F_U, F_U_I, F_HP_PREV_M,
) = range(14)
N_FS = 14
