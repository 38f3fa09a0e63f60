"""The nodes of the OPC UA condition instances (conditions.py), added fast enough for thousands.

asyncua's `instantiate` browses a type's whole hierarchy again for every instance and AddNodes
builds every attribute of every node afresh: about 0.1 s per condition, minutes for a station with
thousands of alarms. Here each standard type's instance declarations are read once per process
(`template`); the first condition of each shape is added through AddNodes, and every other one of
that shape is a copy of its nodes (`clone`), which shares the attribute values that never change.
The station's files (files.py) are FileType objects added the same way (`add_instance`, then
`clone`).
"""

from __future__ import annotations

import copy
from dataclasses import dataclass
from typing import Any

from asyncua import Node, Server, ua
from asyncua.common.copy_node_util import _read_and_copy_attrs
from asyncua.common.ua_utils import get_node_supertypes
from asyncua.server.address_space import AttributeValue, NodeData

_O, _V = ua.ObjectIds, ua.VariantType
OPTIONAL_RULES = (ua.NodeId(_O.ModellingRule_Optional), ua.NodeId(_O.ModellingRule_OptionalPlaceholder))
ATTRIBUTES = {ua.NodeClass.Object: ua.ObjectAttributes, ua.NodeClass.Variable: ua.VariableAttributes,
              ua.NodeClass.Method: ua.MethodAttributes}


@dataclass(frozen=True)
class Declared:
    """One node of a condition type's instances, as the type declares it."""

    path: tuple[str, ...]  # BrowseNames below the condition
    item: ua.AddNodesItem  # class, BrowseName, reference to its parent, type definition, attributes

    @property
    def field(self) -> str:
        """Its name as an event field ("AckedState/Id")."""
        return "/".join(self.path)


_TEMPLATES: dict[tuple[int, frozenset[str]], list[Declared]] = {}  # the standard types': any server's


async def template(server: Server, type_id: int, optional: frozenset[str]) -> list[Declared]:
    """The nodes an instance of the type has, parents before children: the mandatory ones and the
    `optional` ones named (of the condition itself; below it, the mandatory ones only)."""
    key = (type_id, optional)
    if key not in _TEMPLATES:
        out: list[Declared] = []
        types = await get_node_supertypes(server.get_node(type_id), includeitself=True)
        await _children(server, (), types, optional, out)
        _TEMPLATES[key] = out
    return _TEMPLATES[key]


async def _children(server: Server, path: tuple[str, ...], declarations: list[Node], optional: frozenset[str],
                    out: list[Declared]) -> None:
    seen: set[str] = set()  # a subtype's declaration overrides its supertype's
    for declaration in declarations:
        for rdesc in await declaration.get_children_descriptions():
            name = rdesc.BrowseName.Name
            if name in seen:
                continue
            child = server.get_node(rdesc.NodeId)
            rules = await child.get_referenced_nodes(refs=_O.HasModellingRule)
            if not rules:  # no part of an instance (a subtype, a type's own method)
                continue
            if rules[0].nodeid in OPTIONAL_RULES and (path or name not in optional):
                continue
            seen.add(name)
            typedef = rdesc.TypeDefinition
            item = ua.AddNodesItem(BrowseName=rdesc.BrowseName, ReferenceTypeId=rdesc.ReferenceTypeId,
                                   NodeClass=rdesc.NodeClass,
                                   TypeDefinition=ua.NodeId(typedef.Identifier, typedef.NamespaceIndex))
            await _read_and_copy_attrs(child, ATTRIBUTES[rdesc.NodeClass](), item)
            out.append(Declared((*path, name), item))
            await _children(server, (*path, name), [child], optional, out)


def own(idx: int, normal: ua.VariantType | None) -> list[Declared]:
    """The station's own properties of a condition: its ISA-18.2 state word, its priority and text,
    and the value its input has when normal (`normal`: that value's type; None: it has none)."""
    names = [("State", _V.String), ("Priority", _V.String), ("Text", _V.String)]
    if normal is not None:
        names.append(("NormalValue", normal))
    out = []
    for name, kind in names:
        attributes = ua.VariableAttributes(
            DisplayName=ua.LocalizedText(name), Value=ua.Variant(False if kind is _V.Boolean else "", kind),
            DataType=ua.NodeId(kind.value), ValueRank=-1, AccessLevel=1, UserAccessLevel=1)
        out.append(Declared((name,), ua.AddNodesItem(
            ReferenceTypeId=ua.NodeId(_O.HasProperty), BrowseName=ua.QualifiedName(name, idx),
            NodeClass=ua.NodeClass.Variable, NodeAttributes=attributes,
            TypeDefinition=ua.NodeId(_O.PropertyType))))
    return out


async def add(server: Server, ids: list[ua.NodeId], declared: list[Declared], folder: ua.NodeId,
              type_id: int, description: str) -> None:
    """A condition's nodes through AddNodes: its root `ids[0]` organized by `folder`, named as its
    NodeId's last part after "Alarms.", then `declared` at `ids[1:]`."""
    root = ids[0]
    name = ua.QualifiedName(root.Identifier.removeprefix("Alarms."), root.NamespaceIndex)
    attributes = ua.ObjectAttributes(DisplayName=ua.LocalizedText(name.Name), EventNotifier=0,
                                     Description=ua.LocalizedText(description))
    item = ua.AddNodesItem(ParentNodeId=folder, ReferenceTypeId=ua.NodeId(_O.Organizes),
                           RequestedNewNodeId=root, BrowseName=name, NodeClass=ua.NodeClass.Object,
                           NodeAttributes=attributes, TypeDefinition=ua.NodeId(type_id))
    await add_instance(server, item, ids, declared)


async def add_instance(server: Server, root: ua.AddNodesItem, ids: list[ua.NodeId],
                       declared: list[Declared]) -> None:
    """An instance's nodes through AddNodes: `root` (at `ids[0]`), then `declared` at `ids[1:]`, each
    below the node its path names."""
    items = [root]
    for d, nodeid in zip(declared, ids[1:]):
        item = copy.copy(d.item)
        item.RequestedNewNodeId = nodeid
        item.ParentNodeId = ua.NodeId(".".join((ids[0].Identifier, *d.path[:-1])), ids[0].NamespaceIndex)
        items.append(item)
    for item, result in zip(items, await server.iserver.isession.add_nodes(items)):
        if not result.StatusCode.is_good():
            raise RuntimeError(f"node {item.RequestedNewNodeId.to_string()} not added: {result.StatusCode}")


def clone(aspace: Any, first: list[ua.NodeId], ids: list[ua.NodeId], description: str | None,
          name: str | None = None) -> None:
    """An instance's nodes (`ids`, its root first) as copies of `first`'s, an instance of the same
    shape added by `add` or `add_instance`, named `name` (a condition: its NodeId's last part after
    "Alarms."), described by `description` (None: as `first`). The copies share the attribute
    values that never change: only a node's Value is ever written, by the station (clients' writes
    are the station's commands, which refuse every node but a tag's value)."""
    remap = dict(zip(first, ids))
    root = ids[0]
    name = ua.QualifiedName(root.Identifier.removeprefix("Alarms.") if name is None else name,
                            root.NamespaceIndex)
    text = ua.LocalizedText(name.Name)
    value_id, node_id = ua.AttributeIds.Value, ua.AttributeIds.NodeId
    for old, new in zip(first, ids):
        original = aspace[old]
        node = NodeData(new)
        node.attributes = dict(original.attributes)
        node.attributes[node_id] = AttributeValue(ua.DataValue(ua.Variant(new, _V.NodeId)))
        if value_id in original.attributes:
            node.attributes[value_id] = AttributeValue(original.attributes[value_id].value)
        node.references = [ref if ref.NodeId not in remap else
                           _pointing(ref, root, name, text) if ref.NodeId == first[0] else
                           _pointing(ref, remap[ref.NodeId], ref.BrowseName, ref.DisplayName)
                           for ref in original.references]
        aspace[new] = node
    node = aspace[root]
    named = [(ua.AttributeIds.BrowseName, ua.Variant(name, _V.QualifiedName)),
             (ua.AttributeIds.DisplayName, ua.Variant(text, _V.LocalizedText))]
    if description is not None:
        named.append((ua.AttributeIds.Description,
                      ua.Variant(ua.LocalizedText(description), _V.LocalizedText)))
    for attribute, value in named:
        node.attributes[attribute] = AttributeValue(ua.DataValue(value))
    up = next(r for r in node.references if not r.IsForward and r.ReferenceTypeId == ua.NodeId(_O.Organizes))
    typedef = next(r.NodeId for r in node.references if r.ReferenceTypeId == ua.NodeId(_O.HasTypeDefinition))
    aspace[up.NodeId].references.append(ua.ReferenceDescription(  # the folder's reference to it
        ReferenceTypeId=up.ReferenceTypeId, IsForward=True, NodeId=root, BrowseName=name, DisplayName=text,
        NodeClass=ua.NodeClass.Object, TypeDefinition=typedef))


def _pointing(ref: ua.ReferenceDescription, to: ua.NodeId, name: ua.QualifiedName,
              text: ua.LocalizedText) -> ua.ReferenceDescription:
    return ua.ReferenceDescription(ReferenceTypeId=ref.ReferenceTypeId, IsForward=ref.IsForward, NodeId=to,
                                   BrowseName=name, DisplayName=text, NodeClass=ref.NodeClass,
                                   TypeDefinition=ref.TypeDefinition)


def reference(source: ua.NodeId, kind: int, target: ua.NodeId,
              target_class: ua.NodeClass) -> ua.AddReferencesItem:
    return ua.AddReferencesItem(SourceNodeId=source, ReferenceTypeId=ua.NodeId(kind), IsForward=True,
                                TargetNodeId=target, TargetNodeClass=target_class)
