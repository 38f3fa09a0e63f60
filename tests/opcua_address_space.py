"""asyncua's standard address space, filled once per test process and copied for each server.

Every OPC UA server the station starts first fills the standard address space of OPC UA Part 5
(6,000 nodes: 3 s of CPU, most of a station's start with OPC UA) and only then adds its own nodes;
the tests start dozens of them. One fill per process, made outside any server before the first
test that may start one, is kept untouched, and each server gets a copy with nodes, attribute
records and reference lists of its own, as a fresh fill would give it. The attribute values
themselves are shared: a server never changes a stored value in place (a write stores a new
DataValue), except that a caller may append to an array it read (`Server.register_namespace`
does), so array values are copied too.
"""

from __future__ import annotations

import copy
from typing import Any

_installed = False


def _copy(nodes: dict[Any, Any]) -> dict[Any, Any]:
    from asyncua.server.address_space import AttributeValue, NodeData

    out = {}
    for nodeid, data in nodes.items():
        node = NodeData(nodeid)
        for attribute, record in data.attributes.items():
            assert record.value_callback is None and record.value_setter is None and \
                not record.datachange_callbacks, f"{nodeid}: a callback in the standard address space"
            value = record.value
            if value is not None and value.Value is not None and isinstance(value.Value.Value, list):
                value, variant = copy.copy(value), copy.copy(value.Value)
                variant.Value = list(variant.Value)
                value.Value = variant
            node.attributes[attribute] = AttributeValue(value)
        node.references = list(data.references)
        assert data.call is None, f"{nodeid}: a method callback in the standard address space"
        out[nodeid] = node
    return out


def fill_once() -> bool:
    """From now on, servers of this process copy the standard address space filled here, outside
    any server (True: filled now, the caller may freeze it out of the collector's way)."""
    global _installed
    if _installed:
        return False
    from asyncua.server.address_space import AddressSpace, NodeManagementService
    from asyncua.server.internal_server import InternalServer
    from asyncua.server.standard_address_space import standard_address_space

    aspace = AddressSpace()
    standard_address_space.fill_address_space(NodeManagementService(aspace))
    first = aspace._nodes  # untouched: no server holds it
    fill = InternalServer.load_standard_address_space

    async def load_standard_address_space(self: InternalServer, shelf_file: Any = None) -> None:
        if shelf_file is not None:
            await fill(self, shelf_file)
            return
        self.aspace._nodes.update(_copy(first))

    InternalServer.load_standard_address_space = load_standard_address_space  # type: ignore[method-assign]
    _installed = True
    return True
