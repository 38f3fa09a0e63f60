"""The Modbus stack: endpoints, the lean TCP client and the pymodbus one, our Modbus TCP server,
RTU framing, and the CPU-165 Modbus map (how NetPlc memory looks as coils and registers).

It is the wire and nothing more: what NODE/NREAD/NWRITE mean is `netplc/exchange.py`, what a
simulated CPU-165 node is is `netplc/simulator.py`; both reach the wire through this package.
Only this package imports pymodbus, whose API changes at every minor release.
"""

from netplc.modbus.client import LeanTcpClient, ModbusClient, open_client
from netplc.modbus.endpoint import Endpoint, parse_endpoint
from netplc.modbus.loop import LoopThread
from netplc.modbus.map import (
    MAX_READ_BITS,
    MAX_READ_REGISTERS,
    PROFILES,
    TABLES,
    WRITABLE_TABLES,
    Block,
    MapError,
    Table,
    bytes_from_words,
    describe,
    locate,
)
from netplc.modbus.pdu import DeviceError, LinkError
from netplc.modbus.server import ALL_MEMORY, ModbusServer
from netplc.modbus.tcp_server import ServerLimits

__all__ = [
    "ALL_MEMORY",
    "MAX_READ_BITS",
    "MAX_READ_REGISTERS",
    "PROFILES",
    "TABLES",
    "WRITABLE_TABLES",
    "Block",
    "DeviceError",
    "Endpoint",
    "LeanTcpClient",
    "LinkError",
    "LoopThread",
    "MapError",
    "ModbusClient",
    "ModbusServer",
    "ServerLimits",
    "Table",
    "bytes_from_words",
    "describe",
    "locate",
    "open_client",
    "parse_endpoint",
]
