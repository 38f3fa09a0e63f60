"""A Modbus RTU slave on a serial line: how a simulated CPU-165 node answers NetPlc over RS-485.

On a shared bus the slave hears everything: requests to every unit and the other slaves' answers,
often back to back with no 3.5-character silence between them (a USB adapter also splits and
merges frames as it likes). So frames are found by their length and CRC, never by timing alone:
at each position the bytes are tried as a request and as an answer, each with the length its
function code gives (pymodbus's PDU classes know the lengths of every function code, both ways),
and a frame counts only when its CRC holds. Bytes that are neither are skipped one at a time
(hunting), so the slave is back in step at the next frame rather than after a silence. A request
of a code no table knows is found by the shortest length whose CRC holds. A silence of the line
ends whatever is left as noise.

Requests for another unit are left unanswered, as a device does; a broadcast (unit 0) write is
done without a reply, a broadcast read is not done at all. The answers come from `answer`, the
same request handling the TCP server uses; a write is answered once its handler has applied and
journaled it. A serial port that fails (an adapter unplugged) is a fault: journaled once, shown
by `fault`, and the port is reopened every second until it works again.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import threading
from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol

import serial

from netplc.modbus.endpoint import Endpoint
from netplc.modbus.pdu import ServeHandler, answer
from netplc.words import Say, english

if TYPE_CHECKING:
    from pymodbus.pdu import DecodePDU

BROADCAST = 0
MAX_FRAME = 256  # an RTU frame's longest: unit, 253 bytes of PDU, CRC
MIN_FRAME = 4  # unit, function code, CRC
WRITE_WAIT = 5.0  # s a write may wait for its scan and journal record before it goes unanswered
REOPEN = 1.0  # s between attempts to reopen a failed serial port
_READS = frozenset((1, 2, 3, 4))


def crc16(data: bytes | bytearray) -> bytes:
    """The Modbus RTU CRC (polynomial 0xA001, start 0xFFFF), low byte first as sent."""
    crc = 0xFFFF
    for b in data:
        crc ^= b
        for _ in range(8):
            crc = (crc >> 1) ^ 0xA001 if crc & 1 else crc >> 1
    return crc.to_bytes(2, "little")


@functools.cache
def _decoder(requests: bool) -> DecodePDU:
    """pymodbus's decoder of requests (or answers), made at first use: pymodbus loads only for a
    serial line, not for every station that imports the stack."""
    from pymodbus.pdu import DecodePDU

    return DecodePDU(is_server=requests)


def _length(decoder: DecodePDU, buf: bytes | bytearray) -> int | None:
    """The frame length the function code at buf[1] gives: 0 while too few bytes tell it, None
    for a code the decoder does not know."""
    try:
        pdu = decoder.lookupPduClass(bytes(buf[:8]))
        return None if pdu is None else pdu.calculateRtuFrameSize(bytes(buf))
    except IndexError:  # a sub-function code not arrived yet
        return 0


def request_length(buf: bytes | bytearray) -> int | None:
    """Length of the request at the start of `buf`: 0 while too few bytes tell it, None when the
    function code does not tell it."""
    if len(buf) < 2:
        return 0
    return _length(_decoder(True), buf)


def take_frames(buf: bytearray, silent: bool = False) -> tuple[list[bytes], int]:
    """Remove the whole frames from the front of `buf`: the requests found (answers of other
    slaves are skipped) and the number of noise bytes skipped. `silent`: the line fell silent, so
    no more bytes will complete what is left; it is tried as a frame of unknown length, then dropped."""
    requests: list[bytes] = []
    pos, skipped, end = 0, 0, len(buf)
    while end - pos >= MIN_FRAME:
        head = buf[pos : pos + MAX_FRAME]
        sizes = ((_length(_decoder(True), head), 1), (_length(_decoder(False), head), -1))
        known = any(size is not None for size, _ in sizes)
        waiting = not known and head[1] != 0  # a code no table knows: its CRC, or the silence, ends it
        found = 0
        for size, sign in sizes:
            if size is None:
                continue
            if size == 0 or size > len(head):
                waiting = True
                continue
            if size >= MIN_FRAME and crc16(head[: size - 2]) == head[size - 2 : size]:
                found = sign * size
                break
        if not found and not known and head[1] != 0:
            found = _by_crc(head)
        if found > 0:
            requests.append(bytes(head[:found]))
            pos += found
        elif found < 0:
            pos -= found
        elif waiting and not silent:
            break
        else:
            pos += 1
            skipped += 1
    if silent:
        skipped += end - pos
        pos = end
    del buf[:pos]
    return requests, skipped


def _by_crc(head: bytes | bytearray) -> int:
    """A request of a code no table knows: the shortest length whose CRC holds (0: none yet)."""
    for size in range(MIN_FRAME, len(head) + 1):
        if crc16(head[: size - 2]) == head[size - 2 : size]:
            return size
    return 0


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
    """Answers `handler` as unit `unit` (None: every unit) on `line`, from a thread of its own.

    `reopen()` opens the port again after a failure (None: keep the same line); `note(text)`
    journals the port's faults and recoveries. `line` None: the port could not be opened yet
    (`start(fault)` says why), so the thread opens it with `reopen` first."""

    def __init__(self, handler: ServeHandler, unit: int | None, line: SerialLine | None, name: str,
                 reopen: Callable[[], SerialLine] | None = None,
                 note: Callable[[str], None] | None = None, words: Say = english) -> None:
        self.handler = handler
        self.words = words  # the station's words for its records (netplc/words.py)
        self.unit = unit
        self.line = line
        self.name = name  # the port, for journal records and thread names
        self.reopen = reopen
        self.note = note or logging.getLogger(__name__).error
        self.answered = 0
        self.ignored = 0  # frames with a bad CRC, too short, or for another unit; noise bytes
        self.fault = ""  # the serial port's failure while it lasts
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._serve, name=f"modbus-rtu-{name}", daemon=True)

    def start(self, fault: str = "") -> None:
        """`fault`: why the port is not open (`line` None); shown as `fault` until it opens. The
        caller journals it, naming its own setting."""
        if self.line is None and self.reopen is None:
            raise ValueError("an RtuServer without a line needs `reopen` to open one")
        self.fault = fault
        self._thread.start()

    @property
    def thread_alive(self) -> bool:
        return self._thread.is_alive()

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(2.0)
        self._close()

    def _close(self) -> None:
        if self.line is not None:
            with contextlib.suppress(OSError):
                self.line.close()

    def _serve(self) -> None:
        buf = bytearray()
        if self.line is None:
            self._reopen()
        while not self._stop.is_set():
            assert self.line is not None
            try:
                chunk = self.line.read(MAX_FRAME)
            except OSError as e:
                buf.clear()
                self._failed(e)
                continue
            buf += chunk
            frames, skipped = take_frames(buf, silent=not chunk)
            self.ignored += skipped
            for request in frames:
                try:
                    self.frame(request)
                except OSError as e:
                    self._failed(e)
                    break

    def _failed(self, error: OSError) -> None:
        """The port failed: say so once, then try it again every REOPEN seconds until it works."""
        self.fault = self.words("rtu failed", port=self.name, error=error)
        self.note(self.words("rtu retrying", fault=self.fault, every=REOPEN))
        self._reopen()

    def _reopen(self) -> None:
        while not self._stop.wait(REOPEN):
            if self.reopen is None:
                break
            self._close()
            try:
                self.line = self.reopen()
            except OSError:
                continue
            break
        if not self._stop.is_set():
            self.note(self.words("rtu works", port=self.name))
            self.fault = ""

    def frame(self, frame: bytes) -> bytes | None:
        """Handle one request frame; the reply sent (None: none is due)."""
        if len(frame) < MIN_FRAME or crc16(frame[:-2]) != frame[-2:]:
            self.ignored += 1
            return None
        unit, pdu = frame[0], frame[1:-2]
        if unit == BROADCAST:
            if pdu[0] in _READS:  # a broadcast read has nobody to answer: not done
                self.ignored += 1
                return None
        elif self.unit is not None and unit != self.unit:
            self.ignored += 1
            return None
        later: list[bytes] = []
        done = threading.Event()

        def written(response: bytes) -> None:
            later.append(response)
            done.set()

        response = answer(self.handler, pdu, f"rtu {self.name}", written)
        if unit == BROADCAST:
            return None
        if response is None:  # a write: answered once applied and journaled
            if not done.wait(WRITE_WAIT):
                return None
            response = later[0]
        reply = bytes([unit]) + response
        reply += crc16(reply)
        self.line.write(reply)
        self.answered += 1
        return reply
