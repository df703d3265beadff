"""Gateway: exposes the simulated house as real devices over Modbus TCP/RTU and CANopen."""
