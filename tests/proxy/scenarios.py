"""Client scenarios (pltf.client, the Python client library) to record through the proxy and replay."""

from __future__ import annotations

import socket

from pltf.client import MotionMode, OperationState, PlatformClient, format_param_value

AUTOMATIC, VEL = MotionMode.MODE_MOTION_AUTOMATIC, MotionMode.MODE_MOTION_VEL
READY, RUNNING = OperationState.ST_OP_READY, OperationState.ST_OP_RUNNING


def drive(port: int) -> None:
    """Bring up, read the parameters, drive 500 mm in Automatic, try to change the mode while Running (guide
    6.3 CMD_SET_MODE: only in Ready, so the mode stays), stop."""
    with PlatformClient("127.0.0.1", port, timeout=5) as pltf:
        pltf.bring_up(timeout=10)
        entries = pltf.get_pltf_param_vec().parameters
        pltf.get_pltf_param(entries[0].key)
        pltf.set_mode(AUTOMATIC)
        pltf.wait_mode(AUTOMATIC, timeout=5)
        pltf.start()
        pltf.wait_state(RUNNING, timeout=5)
        pltf.get_position()
        pltf.move_rel(x_mm=500, y_mm=0, angle_mdeg=0)
        pltf.wait_target_reached(timeout=20)
        pltf.get_position()
        pltf.set_mode(VEL)  # refused in Running
        pltf.get_status()
        pltf.stop()
        pltf.wait_state(READY, timeout=5)


def parameters(port: int) -> None:
    """On the other port: the camera, the map's name, a parameter written and read back and restored."""
    with PlatformClient("127.0.0.1", port, timeout=5) as pltf:
        pltf.get_camera()
        pltf.get_map()
        old = pltf.get_pltf_param("IpoTransVel").value
        pltf.set_pltf_param("IpoTransVel", format_param_value(800))
        pltf.get_pltf_param("IpoTransVel")
        pltf.set_pltf_param("IpoTransVel", format_param_value(99999))  # out of range: refused
        pltf.get_pltf_param("IpoTransVel")
        pltf.set_pltf_param("IpoTransVel", old)


def garbage(port: int) -> None:
    """A client that sends a frame with a bad header: the target closes the connection (erratum E-WIRE-006)."""
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(bytes.fromhex("ff01fe020000000112") + bytes.fromhex("ff01fe030000000112"))
        while s.recv(65536):
            pass


def all_scenarios(ports: list[int]) -> None:
    drive(ports[0])
    parameters(ports[1])
    garbage(ports[1])
