"""Bench emulators: small models of the lab's PHIL benches, served as their bench maps describe."""
