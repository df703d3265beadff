"""Device maps: the DeviceMap/Point model, the codec, lint, register-table export and CSV import."""
