"""A node's connection through pymodbus: Modbus RTU on a serial port, and Modbus TCP where
bench/exchange.py compares it with our lean client.

pymodbus changes its API at every minor release (docs/architecture.md section 7), so this is the
only client module that imports it, and nothing of pymodbus leaks out. Retries and reconnect
back-off belong to the exchange, so its clients are built with `retries=0` and
`reconnect_delay=0` (no reconnect task of their own).
"""

from __future__ import annotations

import logging
import struct
from collections.abc import Awaitable
from typing import Any

from pymodbus.client import AsyncModbusSerialClient, AsyncModbusTcpClient
from pymodbus.exceptions import ModbusException
from pymodbus.framer import FramerType

from netplc.modbus.endpoint import Endpoint
from netplc.modbus.map import BIT_TABLES, MapError, Table, bytes_from_bits
from netplc.modbus.pdu import MBAP, READ_CODES, READ_TABLES, DeviceError, LinkError, ProtocolError

try:  # pyserial sets a POSIX port up through termios, whose error is not an OSError
    from termios import error as _termios_error

    PORT_ERRORS: tuple[type[Exception], ...] = (_termios_error,)
except ImportError:  # Windows: pyserial's SerialException is an OSError
    PORT_ERRORS = ()

# pymodbus logs every refused connect and every timeout; the exchange reports link changes itself
# (node statistics and 'system' records), so a dead node must not flood the log.
logging.getLogger("pymodbus").setLevel(logging.CRITICAL)


class PymodbusClient:
    """A node's connection through pymodbus (TCP or RTU)."""

    def __init__(self, endpoint: Endpoint, timeout: float) -> None:
        self.endpoint = endpoint
        self.timeout = timeout
        self._client: AsyncModbusTcpClient | AsyncModbusSerialClient | None = None
        self._malformed = ""  # what the last TCP frame received had wrong (pymodbus decodes leniently)

    def _make(self) -> AsyncModbusTcpClient | AsyncModbusSerialClient:
        ep = self.endpoint
        if ep.scheme == "tcp":
            return AsyncModbusTcpClient(ep.host, port=ep.port, timeout=self.timeout, retries=0,
                                        reconnect_delay=0, trace_packet=self._inspect)
        return AsyncModbusSerialClient(ep.device, framer=FramerType.RTU, baudrate=ep.baudrate,
                                       parity=ep.parity, bytesize=ep.bytesize, stopbits=ep.stopbits,
                                       timeout=self.timeout, retries=0, reconnect_delay=0)

    @property
    def connected(self) -> bool:
        return self._client is not None and self._client.connected

    async def connect(self) -> None:
        """A port that the system will not open or set up as asked (no such device, a setting the
        driver refuses: termios says EINVAL for parity on a pty) is a link fault with the
        system's reason, not an internal error of the exchange."""
        self.close()
        self._client = self._make()
        try:
            connected = await self._client.connect()
        except (OSError, ValueError, *PORT_ERRORS) as e:
            self.close()
            reason = OSError(*e.args) if isinstance(e, PORT_ERRORS) else e  # "[Errno 22] Invalid argument"
            raise LinkError(f"cannot open {self.endpoint}: {reason}") from e
        if not connected:
            self.close()
            raise LinkError(f"cannot connect to {self.endpoint}")

    def close(self) -> None:
        if self._client is not None:
            self._client.close()
            self._client = None

    def _inspect(self, sending: bool, data: bytes) -> bytes:
        """pymodbus hands over what a TCP connection received: a read answer whose byte count is
        not what its frame holds is malformed, though pymodbus would decode what it can of it."""
        if not sending:
            pos = 0
            while len(data) - pos >= 9:
                length = MBAP.unpack_from(data, pos)[2]
                pdu = data[pos + 7 : pos + 6 + length]
                if len(pdu) < length - 1:
                    break
                if pdu[0] in READ_TABLES and (len(pdu) != 2 + pdu[1] or (pdu[0] > 2 and pdu[1] % 2)):
                    self._malformed = f"answer of {len(pdu)} bytes with byte count {pdu[1]}"
                pos += 6 + length
        return data

    async def _call(self, what: str, request: Awaitable[Any], fc: int) -> Any:
        """The answer to a request of function `fc`: a DeviceError for a Modbus exception, a
        LinkError for no answer, a ProtocolError for an answer to another function."""
        self._malformed = ""
        try:
            response = await request
        except (TimeoutError, ModbusException, OSError) as e:
            raise LinkError(f"{what}: {e}") from None
        if self._malformed:
            raise ProtocolError(f"{what}: {self._malformed}")
        if response.isError():
            raise DeviceError(getattr(response, "exception_code", 4), what)
        if getattr(response, "function_code", None) != fc:
            raise ProtocolError(f"{what}: answer with function {getattr(response, 'function_code', '?')}")
        return response

    async def read(self, unit: int, table: Table, address: int, count: int) -> list[int]:
        """`count` registers or bits of `table` from `address` of device `unit`."""
        c = self._client
        if c is None:
            raise LinkError(f"not connected to {self.endpoint}")
        what = f"read {table} {address}+{count}"
        calls = {"coils": c.read_coils, "discrete": c.read_discrete_inputs,
                 "holding": c.read_holding_registers, "input": c.read_input_registers}
        rr = await self._call(what, calls[table](address, count=count, device_id=unit), READ_CODES[table])
        if table in BIT_TABLES:
            if len(rr.bits) != 8 * ((count + 7) // 8):
                raise ProtocolError(f"{what}: {len(rr.bits)} coils in the answer")
            return [1 if b else 0 for b in rr.bits[:count]]
        if len(rr.registers) != count:
            raise ProtocolError(f"{what}: {len(rr.registers)} registers in the answer")
        return list(rr.registers)

    async def read_bytes(self, unit: int, table: Table, address: int, count: int) -> bytes:
        values = await self.read(unit, table, address, count)
        if table in BIT_TABLES:
            return bytes_from_bits(values)
        return struct.pack(f">{count}H", *values)

    async def write(self, unit: int, table: Table, address: int, values: list[int]) -> None:
        c = self._client
        if c is None:
            raise LinkError(f"not connected to {self.endpoint}")
        what = f"write {table} {address}+{len(values)}"
        if table == "coils":
            rr = await self._call(what, c.write_coils(address, [bool(v) for v in values], device_id=unit), 15)
        elif table == "holding":
            rr = await self._call(what, c.write_registers(address, values, device_id=unit), 16)
        else:
            raise MapError(f"{table} is a read-only table")
        if (rr.address, rr.count) != (address, len(values)):
            raise ProtocolError(f"{what}: the answer echoes {rr.address}+{rr.count}")
