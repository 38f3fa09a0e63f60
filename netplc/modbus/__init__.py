"""The Modbus stack: endpoints, the lean TCP client and the pymodbus one, our Modbus TCP server,
RTU framing, the exchange's TCP frames encoded once (`frames.py`), and the CPU-165 Modbus map (how
NetPlc memory looks as coils and registers).

It is the wire and nothing more: what NODE/NREAD/NWRITE mean is `netplc/exchange.py`, what a
simulated CPU-165 node is is `netplc/simulator.py`; both reach the wire through this package. What
a write to our server does is its handler's (the station's command layer, a simulated node's
engine): the stack imports no engine. Only this package imports pymodbus, whose API changes at
every minor release.
"""

from netplc.modbus.client import LeanTcpClient, ModbusClient, open_client
from netplc.modbus.endpoint import Endpoint, default_stopbits, line_problems, parse_endpoint
from netplc.modbus.frames import Frame, FrameError, answer_data, frame_size
from netplc.modbus.loop import LoopThread
from netplc.modbus.map import (
    MAX_READ_BITS,
    MAX_READ_REGISTERS,
    PROFILES,
    TABLES,
    WRITABLE_TABLES,
    Block,
    MapError,
    MemoryWrite,
    Table,
    bytes_from_words,
    describe,
    locate,
)
from netplc.modbus.pdu import (
    APPLIED,
    BUSY,
    DEVICE_FAILURE,
    EXCEPTIONS,
    ILLEGAL_ADDRESS,
    ILLEGAL_FUNCTION,
    ILLEGAL_VALUE,
    DeviceError,
    Done,
    LinkError,
    ServeHandler,
    exception_text,
)
from netplc.modbus.reactor import Reactor
from netplc.modbus.rtu import REOPEN
from netplc.modbus.server import ALL_MEMORY, MemoryServed, ModbusServer
from netplc.modbus.tcp_server import ServerLimits

__all__ = [
    "ALL_MEMORY",
    "APPLIED",
    "BUSY",
    "DEVICE_FAILURE",
    "EXCEPTIONS",
    "ILLEGAL_ADDRESS",
    "ILLEGAL_FUNCTION",
    "ILLEGAL_VALUE",
    "MAX_READ_BITS",
    "MAX_READ_REGISTERS",
    "PROFILES",
    "REOPEN",
    "TABLES",
    "WRITABLE_TABLES",
    "Block",
    "DeviceError",
    "Done",
    "Endpoint",
    "Frame",
    "FrameError",
    "LeanTcpClient",
    "LinkError",
    "LoopThread",
    "MapError",
    "MemoryServed",
    "MemoryWrite",
    "ModbusClient",
    "ModbusServer",
    "Reactor",
    "ServeHandler",
    "ServerLimits",
    "Table",
    "answer_data",
    "bytes_from_words",
    "default_stopbits",
    "describe",
    "exception_text",
    "frame_size",
    "line_problems",
    "locate",
    "open_client",
    "parse_endpoint",
]
