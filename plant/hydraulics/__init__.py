"""The coupling point between generators, storage and consumers (one interface, swappable models)."""
