"""Generator and storage component models (one module per unit: Params, STATES, initial_state, tables, njit kernel)."""
