"""Device emulators: the simulated robot behind the real wire protocols (Nomad 200 serial, the
CAN sonar board), so drivers are tested end to end without hardware. They reuse the drivers'
pure codecs."""
