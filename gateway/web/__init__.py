"""Live view of a running gateway: a browser page and a small JSON API (see server.py)."""
