"""Time series that drive the house: weather, occupancy, household electricity, hot-water draws."""
