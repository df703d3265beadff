"""Device runtime: a map plus live state and logic, shared by every transport."""
