"""Connection kinds: what joins components (coupling point, coil), each a kind the compiler knows."""
