"""Where everything lives in the flat arrays the numerical core works on: the parameter vector
``P`` (filled by rigsim.model.build), the channels, the ledger, the aux record, and the core's own
state arrays (lumped nodes, controller and generator states, probes, per-step losses)."""

CP = 4186.0  # J/(kg K), water

# ---- parameter vector indices -------------------------------------------------------------
(I_DT, I_TROOM, I_B_M, I_B_KC, I_D_M, I_D_KC,
 I_C_CHP, I_UA_CHP, I_C_BOI, I_UA_BOI,
 I_CHP_MMIN, I_CHP_KP, I_CHP_MMAX, I_CHP_TREG, I_CHP_RUNON, I_CHP_PELMAX, I_CHP_ETAEL,
 I_BOI_MMIN, I_BOI_MMAX, I_BOI_KP, I_BOI_DT, I_BOI_RUNON, I_BOI_HF, I_BOI_PNOM, I_BOI_ETAMAX,
 I_C_SH, I_C_RH, I_UA_HDR,
 I_C_SEG, I_UA_SEG,
 I_C_RAD, I_K_RAD, I_N_RAD,
 I_C_A, I_C_M, I_H_AO, I_H_AM, I_H_MO, I_H_MG, I_F_CONV, I_A_SOL, I_N_PERS, I_W_PERS,
 I_PUMP_MAX, I_T_RUN, I_KP_V, I_KI_V, I_LEAK,
 I_M_CHG, I_IDLE_K,
 I_TAU_PROBE, I_TAU_ROOM, I_M_HCS, I_TAU_HCS,
 I_T_COLD, I_T_DHW, I_HC_TSET, I_T_DAY, I_T_NIGHT, I_BOI_TMAX,
 I_HC_RUNON, I_HC_TCLOSE, I_HC_FRUNON,
 N_PARAM) = range(64)

N_CH = 38
# channel indices (order of house1-channels.csv without t_s)
C_CHP_ON, C_CHP_MOD, C_CB_MOD, C_DHW_CMD, C_HC_TSET, C_HC_FSET, C_OUT = 0, 1, 2, 3, 4, 5, 6
C_BT0 = 7        # BT_T01..BT_T10 -> 7..16
C_WWS0 = 17      # WWS_T1..3 -> 17..19
(C_CHP_TVL, C_CHP_TRL, C_CHP_PEL, C_CHP_QTH, C_CHP_PGAS,
 C_CB_TVL, C_CB_TRL, C_CB_FLOW, C_CB_QTH, C_CB_PGAS,
 C_HC_TVL, C_HC_TRL, C_HC_FLOW, C_DHW_CHG, C_DHW_TAP, C_HDR_TVL, C_HDR_TRL, C_ROOM) = range(20, 38)

# ledger slots [J]
(L_FUEL, L_EL, L_GENLOSS, L_PIPELOSS, L_STORELOSS, L_BUILDING, L_DHW, L_E0, L_E1,
 L_IDLE_MASS, L_IDLE_TIME, L_TMIN, L_TMAX, N_LEDGER) = range(14)

# aux record per sample
(A_M_CHP, A_CHP_STATE, A_M_TANK, A_U_VALVE, A_Q_RAD, A_SOC, N_AUX) = range(7)

# lumped nodes (the `nodes` argument of core.run): generators, pipes (CHP/boiler supply and
# return), headers, room air and building mass
(N_CHP, N_BOI, N_PCS, N_PCR, N_PBS, N_PBR, N_SH, N_RH, N_A, N_M, N_NODES) = range(11)

# integer states: PLC commands and the generators' run and lock-out flags
(S_CHP_CMD, S_BOI_CMD, S_DHW_CMD, S_HC_ON, S_CHP_RUN, S_BOI_RUN, S_BOI_LOCK, N_ISTATE) = range(8)
# float states: PLC outputs, generator switching times and last flows, mixing-valve PI, the
# circuit's supply set-point and the seconds of its pump run-on left
(F_FLOW_SET, F_SOC, F_CHP_TON, F_CHP_TOFF, F_CHP_MLAST, F_M_C_PREV,
 F_BOI_TON, F_BOI_TOFF, F_BOI_MLAST, F_M_B_PREV, F_U, F_I_V, F_TSET, F_HC_RUN, N_FSTATE) = range(15)

# probe states: thermowells of pipes, headers and circuit return, circuit supply pipe, room
(PR_CS, PR_CR, PR_BS, PR_BR, PR_SH, PR_RH, PR_HCR, PR_HCS, PR_ROOM, N_PROBE) = range(10)

# losses of one step [W]: generators, pipes, headers
(LO_CHP, LO_BOI, LO_P0, LO_P1, LO_P2, LO_P3, LO_SH, LO_RH, N_LOSS) = range(9)
