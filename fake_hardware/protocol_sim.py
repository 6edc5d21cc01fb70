"""pyserial URL handler ``sim://``: an in-memory loopback for simulated time (what is written is read back).

pyserial finds it through ``serial.protocol_handler_packages`` (``pltf.fake_hardware.serial_scanner`` registers the
package), so ``serial.serial_for_url("sim://")`` works like ``loop://`` with three differences that matter in a
simulation running faster than real time: whole byte strings instead of a queue of single bytes (about 100x
faster), it never blocks (reads return what is there, whatever the timeout), and the buffer is bounded: bytes
beyond ``buffer_size`` (URL option ``?buffer=N``, default 64 KiB) are dropped and counted in ``overruns``, as a
UART's receive FIFO would. A pty is asynchronous in wall-clock time, so it is not deterministic here.
"""

from __future__ import annotations

import urllib.parse
from typing import Any

from serial.serialutil import PortNotOpenError, SerialBase, SerialException  # type: ignore[import-untyped]


class Serial(SerialBase):  # type: ignore[misc]
    is_open: bool
    BAUDRATES = (9600, 19200, 38400, 57600, 115200, 230400, 460800, 500000, 921600)

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        self.buffer = bytearray()
        self.buffer_size = 64 * 1024
        self.overruns = 0  # writes that did not fit completely
        super().__init__(*args, **kwargs)

    def open(self) -> None:
        if self.is_open:
            raise SerialException("Port is already open.")
        if self._port is None:
            raise SerialException("Port must be configured before it can be used.")
        self._from_url(self.port)
        self.buffer = bytearray()
        self.is_open = True

    def close(self) -> None:
        self.is_open = False
        self.buffer = bytearray()

    def _from_url(self, url: str) -> None:
        parts = urllib.parse.urlsplit(url)
        if parts.scheme != "sim":
            raise SerialException(f'expected "sim://[?buffer=N]", not {url!r}')
        for option, values in urllib.parse.parse_qs(parts.query).items():
            if option != "buffer" or not values[0].isdigit() or int(values[0]) <= 0:
                raise SerialException(f"unknown option {option}={values[0]!r} in {url!r}")
            self.buffer_size = int(values[0])

    def _reconfigure_port(self) -> None:
        pass  # nothing to configure: no wire

    def _update_rts_state(self) -> None:
        pass

    def _update_dtr_state(self) -> None:
        pass

    def _update_break_state(self) -> None:
        pass

    @property
    def in_waiting(self) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        return len(self.buffer)

    def read(self, size: int = 1) -> bytes:
        if not self.is_open:
            raise PortNotOpenError()
        data = bytes(self.buffer[:size])
        del self.buffer[:size]
        return data

    def write(self, data: bytes) -> int:
        if not self.is_open:
            raise PortNotOpenError()
        room = self.buffer_size - len(self.buffer)
        if len(data) > room:
            self.overruns += 1
            data = data[: max(0, room)]
        self.buffer += data
        return len(data)

    def reset_input_buffer(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()
        self.buffer.clear()

    def reset_output_buffer(self) -> None:
        if not self.is_open:
            raise PortNotOpenError()

    @property
    def cts(self) -> bool:
        return True

    @property
    def dsr(self) -> bool:
        return True

    @property
    def ri(self) -> bool:
        return False

    @property
    def cd(self) -> bool:
        return True
