"""PHIL: the twin drives the lab's emulator benches (bench maps, bench emulators, the exchange loop)."""
