"""A Modbus RTU slave on a serial line: how a simulated CPU-165 node answers NetPlc over RS-485.

The requests are read whole by their function code's length (a USB serial adapter delivers a frame
in pieces, with gaps longer than the standard's 3.5-character silence), and by silence for a code
that does not tell its length, which then gets exception 1 like any code we do not serve. A frame
with a bad CRC, or addressed to another unit on the line, is left unanswered, as a device does;
a broadcast (unit 0) write is done without a reply. The answers come from `answer`, the same
request handling the TCP server uses.
"""

from __future__ import annotations

import logging
import threading
from typing import Protocol

import serial

from netplc.modbus.driver import Endpoint, ServeHandler, answer

BROADCAST = 0
MAX_FRAME = 256  # an RTU frame's longest: unit, 253 bytes of PDU, CRC
_FIXED = {1: 8, 2: 8, 3: 8, 4: 8, 5: 8, 6: 8}  # request length by function code: unit + 5 + CRC


def crc16(data: bytes) -> bytes:
    """The Modbus RTU CRC (polynomial 0xA001, start 0xFFFF), low byte first as sent."""
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc.to_bytes(2, "little")


def request_length(buf: bytes | bytearray) -> int | None:
    """Length of the request at the start of `buf`: 0 while too few bytes tell it, None when the
    function code does not tell it (the silence after the frame ends it)."""
    if len(buf) < 2:
        return 0
    fc = buf[1]
    if fc in _FIXED:
        return _FIXED[fc]
    if fc in (15, 16):
        return 9 + buf[6] if len(buf) >= 7 else 0
    return None


def silence(baudrate: int) -> float:
    """The 3.5-character silence that ends a frame: 11 bits a character, 1.75 ms above 19200 baud."""
    return 1.75e-3 if baudrate > 19200 else 3.5 * 11 / baudrate


class SerialLine(Protocol):
    """What the slave needs of a serial port (pyserial's Serial has it): `read` returns what has
    arrived when the line falls silent, or b"" after its timeout."""

    def read(self, size: int) -> bytes: ...

    def write(self, data: bytes) -> int | None: ...

    def close(self) -> None: ...


def open_line(endpoint: Endpoint) -> SerialLine:
    """The endpoint's serial port, opened; OSError (pyserial's SerialException is one) if it cannot be."""
    return serial.Serial(endpoint.device, baudrate=endpoint.baudrate, parity=endpoint.parity,
                         bytesize=endpoint.bytesize, stopbits=endpoint.stopbits, timeout=0.1,
                         inter_byte_timeout=silence(endpoint.baudrate))


class RtuServer:
    """Answers `handler` as unit `unit` (None: every unit) on `line`, from a thread of its own."""

    def __init__(self, handler: ServeHandler, unit: int | None, line: SerialLine, name: str) -> None:
        self.handler = handler
        self.unit = unit
        self.line = line
        self.name = name  # the port, for journal records and thread names
        self.answered = 0
        self.ignored = 0  # frames with a bad CRC, too short, or for another unit
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name=f"modbus-rtu-{name}", daemon=True)

    def start(self) -> None:
        self._thread.start()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self.line.close()

    def _serve(self) -> None:
        buf = bytearray()
        while not self._stop.is_set():
            try:
                chunk = self.line.read(MAX_FRAME)
            except OSError as e:  # the adapter was unplugged: say so once and stop serving
                logging.getLogger(__name__).error("Modbus RTU on %s stopped: %s", self.name, e)
                return
            if not chunk:  # silence: what is left is one frame of a code without a known length
                if buf:
                    self.frame(bytes(buf))
                    buf.clear()
                continue
            buf += chunk
            while (n := request_length(buf)) and len(buf) >= n:
                self.frame(bytes(buf[:n]))
                del buf[:n]
            if len(buf) > MAX_FRAME:  # noise that never made a frame
                self.ignored += 1
                buf.clear()

    def frame(self, frame: bytes) -> bytes | None:
        """Handle one request frame; the reply sent (None: none is due)."""
        if len(frame) < 4 or crc16(frame[:-2]) != frame[-2:]:
            self.ignored += 1
            return None
        unit = frame[0]
        if unit != BROADCAST and self.unit is not None and unit != self.unit:
            self.ignored += 1
            return None
        pdu = answer(self.handler, frame[1:-2], f"rtu {self.name}")
        if unit == BROADCAST:
            return None
        reply = bytes([unit]) + pdu
        reply += crc16(reply)
        self.line.write(reply)
        self.answered += 1
        return reply
