"""Transports: one module per protocol, turning frames into Device calls."""
