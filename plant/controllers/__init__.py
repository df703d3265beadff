"""Built-in controllers: the case-study rule set and the building's room thermostat."""
