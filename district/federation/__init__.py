"""The district on a co-simulation engine: the engine adapter (engine.py, the one module that
imports helics), the house and grid federates (one process each) and the launcher."""
