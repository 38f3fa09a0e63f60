"""asyncua's standard address space, filled once per test process and copied for each server.

Every OPC UA server the station starts first fills the standard address space of OPC UA Part 5
(6,000 nodes: 3 s of CPU, most of a station's start with OPC UA) and only then adds its own nodes;
the tests start dozens of them. One fill per process, made outside any server before the first
test that may start one, is kept untouched, and each server gets a copy with nodes, attribute
records and reference lists of its own, as a fresh fill would give it, each node copied when the
server first reaches it (`_Nodes`). The attribute values themselves are shared: a server never
changes a stored value in place (a write stores a new DataValue), except that a caller may append
to an array it read (`Server.register_namespace` does), so array values are copied too.
"""

from __future__ import annotations

import copy
from typing import Any

_installed = False


def _copy(nodeid: Any, data: Any) -> Any:
    from asyncua.server.address_space import AttributeValue, NodeData

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
    return node


class _Nodes(dict):
    """A server's nodes (`AddressSpace._nodes`): those it added, and the kept fill's, each copied at
    its first use: most are never used, and copying all 6,000 up front was a third of a server's
    start. Every way asyncua reaches the nodes (index, get, in, del, keys, items, clear) sees both."""

    def __init__(self, first: dict[Any, Any]) -> None:
        super().__init__()
        self._first = first
        self._gone: set[Any] = set()  # kept nodes the server deleted

    def _kept(self, nodeid: Any) -> bool:
        return nodeid in self._first and nodeid not in self._gone

    def __missing__(self, nodeid: Any) -> Any:
        if not self._kept(nodeid):
            raise KeyError(nodeid)
        node = _copy(nodeid, self._first[nodeid])
        dict.__setitem__(self, nodeid, node)
        return node

    def get(self, nodeid: Any, default: Any = None) -> Any:
        if dict.__contains__(self, nodeid) or self._kept(nodeid):
            return self[nodeid]
        return default

    def __contains__(self, nodeid: object) -> bool:
        return dict.__contains__(self, nodeid) or self._kept(nodeid)

    def __setitem__(self, nodeid: Any, node: Any) -> None:
        dict.__setitem__(self, nodeid, node)
        self._gone.discard(nodeid)

    def __delitem__(self, nodeid: Any) -> None:
        if nodeid not in self:
            raise KeyError(nodeid)
        dict.pop(self, nodeid, None)
        if nodeid in self._first:
            self._gone.add(nodeid)

    def keys(self) -> list[Any]:  # type: ignore[override]
        own = dict.keys(self)
        return [*own, *(k for k in self._first if k not in self._gone and k not in own)]

    def __iter__(self) -> Any:
        return iter(self.keys())

    def __len__(self) -> int:
        return len(self.keys())

    def items(self) -> list[tuple[Any, Any]]:  # type: ignore[override]
        return [(k, self[k]) for k in self.keys()]

    def values(self) -> list[Any]:  # type: ignore[override]
        return [self[k] for k in self.keys()]

    def clear(self) -> None:
        dict.clear(self)
        self._gone = set(self._first)

    def _unsupported(self, *args: Any, **kwargs: Any) -> Any:
        raise NotImplementedError("asyncua's address space does not use this")

    pop = popitem = setdefault = update = copy = _unsupported  # type: ignore[assignment]


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
        assert not self.aspace._nodes, "nodes added before the standard address space"
        self.aspace._nodes = _Nodes(first)

    InternalServer.load_standard_address_space = load_standard_address_space  # type: ignore[method-assign]
    _installed = True
    return True
