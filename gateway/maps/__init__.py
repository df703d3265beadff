"""Device maps: the DeviceMap/Point model, the codec, lint and register-table export."""
