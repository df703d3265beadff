"""A CANopen master commands house 1's district-heating substation in a running district: the
master and the house process share a CAN bus through `twin can-hub` (socketcand over TCP), the
house process talks to the grid process through the engine, and the grid books the extraction."""
import time

import canopen
import numpy as np
import pytest

from district.federation.engine import free_port
from gateway.maps.loader import load_all
from gateway.transports.can_bus import open_bus
from gateway.transports.can_hub import CanHub
from gateway.transports.canopen_od import build_object_dictionary
from profiles.recording import read_recording

from .serving import serve

# the substation's SDO commands and the grid's booking through the engine, not the pace, are
# tested: at 600x a 60 s district step is 100 ms of wall time, an SDO write over the hub ~1 ms
SPEED = 600.0
DAYS = 0.04         # 57.6 min: 5.8 s of wall time
COMMAND_EVERY_S = 15.0 / SPEED     # wall s: the master writes every 15 simulated seconds


@pytest.mark.realtime
def test_a_canopen_master_commands_a_substation_of_a_running_district(tmp_path):
    hub = CanHub(port=0).start()
    try:
        twin, out = serve(tmp_path, f"""
[district]
name = "candistrict"
step = 60.0
[plant]
node = "plant"
[pipes.p1]
from = "plant"
to = "n1"
[houses.house1]
node = "n1"
substation = "off"            # the substation waits for the master's commands
modbus_port = {free_port()}
can = "{hub.spec}"
""", DAYS, SPEED)
        assert f"canopen {hub.spec}" in (out / "logs" / "house1.log").read_text()
        dmap = load_all()["district_substation"]
        master = canopen.Network(open_bus(hub.spec))
        master.connect()
        try:
            node = master.add_node(dmap.canopen.node_id, build_object_dictionary(dmap))
            node.sdo.RESPONSE_TIMEOUT = 2.0
            cmd = node.sdo["commands"]
            t_end = time.monotonic() + DAYS * 86400 / SPEED / 2       # command for half the run
            while time.monotonic() < t_end:
                cmd["house_flow_set"].raw = 900                        # +9 l/min: extraction
                cmd["grid_flow_set"].raw = 600                         # 6 l/min grid side
                time.sleep(COMMAND_EVERY_S)
            extracted = node.sdo["counters"]["e_extracted"].raw
        finally:
            master.disconnect()
        _, stderr = twin.communicate(timeout=60)
        assert twin.returncode == 0, stderr
    finally:
        hub.stop()
    assert extracted > 0                                               # the meter counted (0.1 kWh)
    grid = read_recording(out / "grid")
    M = grid.values[:, grid.names.index("house1.M_extracted")]
    assert M.max() == np.float64(0.1 * 60.0)                           # 6 l/min for whole steps
    print(f"extraction booked in {(M > 0).sum()} of {len(M)} grid steps")
    assert (M > 0).sum() > 10                                          # the grid saw it through the engine
    h1 = read_recording(out / "house1")
    writes = [e for e in h1.events if e["kind"] == "write" and e["transport"] == "canopen"]
    assert writes and all(e["accepted"] == "True" for e in writes)
