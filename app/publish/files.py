"""What a remote console needs of its station, served by the station: its forms, program, symbols,
tags and messages, as OPC UA FileType objects (Part 5 section C.2: Open, Read, GetPosition,
SetPosition, Close; read-only) in the station's `Files` folder, and a `Files.Manifest` variable
naming each file with its SHA-256 and which part of the station it is.

Any OPC UA client reads them (asyncua's `UaFile`, UaExpert); a console (`main.py console`) reads
the manifest, fetches only the files whose hash it has not cached, and watches the manifest: a form
saved at the station changes its hash, and the consoles load it without a restart of either side.
The station looks at its files every FILES_EVERY_S; a file is hashed again only when its size or
modification time changed. Only files inside the station folder are served (never users.json, the
archive or the PKI): a station whose paths leave its folder (`allow_outside`) serves what lies
inside it, and the console says which part it misses.
"""

from __future__ import annotations

import asyncio
import hashlib
import itertools
import json
import logging
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from asyncua import Node, Server, ua
from asyncua.common.copy_node_util import _read_and_copy_attrs

from app.publish import condition_nodes as nodes
from app.station.config import Station

logger = logging.getLogger(__name__)

FILES_EVERY_S = 1.0
MAX_FILE = 16 << 20  # bytes: a form's images stay far below; anything larger is not served
FILE_OPTIONAL = frozenset({"MimeType", "MaxByteStringLength", "LastModifiedTime"})  # what instantiate adds
MAX_OPEN = 256  # handles left open (a client gone without Close): the oldest is forgotten beyond this
PARTS = ("program", "symbols", "tags", "messages")  # single files; "forms" is HMIload, a folder
_READ_MODE = 1  # OpenFileMode.Read
Outputs = ua.CallMethodResult | list[ua.Variant]  # a method's output arguments, or its Bad StatusCode


@dataclass(frozen=True)
class Served:
    """One file as the console sees it: its content as of its last change, and its hash."""

    content: bytes
    sha256: str
    stamp: tuple[int, int]  # size and mtime_ns, to see whether it changed


def station_parts(station: Station) -> dict[str, Path]:
    """The station's files a console loads, by part (forms: the HMIload folder)."""
    paths = dict(zip(PARTS, (station.NetPlcProgram, station.Symbols, station.Tags, station.Messages)))
    paths["forms"] = station.HMIload
    return {part: path for part, path in paths.items() if path is not None}


def _inside(path: Path, root: Path) -> str | None:
    """`path` relative to `root` (resolved already: the scan looks at every file each second)."""
    try:
        return path.resolve().relative_to(root).as_posix()
    except ValueError:
        return None


def manifest_of(station: Station, files: dict[str, Served]) -> str:
    """The manifest's JSON: the station, its language and tick, its parts and its files' hashes."""
    root = station.folder.resolve()
    parts = {part: rel for part, path in station_parts(station).items()
             if (rel := _inside(path, root)) is not None}
    return json.dumps({"station": station.name, "language": station.Language, "tick_ms": station.NetSyncTime,
                       "parts": parts, "files": {rel: f.sha256 for rel, f in sorted(files.items())}},
                      ensure_ascii=False, sort_keys=True)


def scan(station: Station, before: dict[str, Served]) -> dict[str, Served]:
    """The files to serve now (off the server's loop: it reads the disk)."""
    folder = station.folder.resolve()
    found: list[Path] = []
    for part, path in station_parts(station).items():
        if _inside(path, folder) is None:
            continue
        found += sorted(p for p in path.rglob("*") if p.is_file()) if part == "forms" else [path]
    out: dict[str, Served] = {}
    for path in found:
        rel = _inside(path, folder)
        try:
            st = path.stat()
            if rel is None or st.st_size > MAX_FILE:
                continue
            stamp = (st.st_size, st.st_mtime_ns)
            old = before.get(rel)
            if old is not None and old.stamp == stamp:
                out[rel] = old
                continue
            content = path.read_bytes()
        except FileNotFoundError:
            continue  # removed while looked at: gone from the next manifest
        except OSError:
            logger.exception("%s: not served to consoles", path)
            continue
        out[rel] = Served(content, hashlib.sha256(content).hexdigest(), stamp)
    return out


class StationFiles:
    """The `Files` folder of the station's address space, kept up to date on the server's loop."""

    def __init__(self, station: Station) -> None:
        self.station = station
        self.files: dict[str, Served] = {}
        self._nodes: dict[str, Node] = {}
        self._handles: dict[int, list[Any]] = {}  # handle -> [content as opened, position]
        self._next = itertools.count(1)
        self._server: Server | None = None
        self._folder: Node | None = None
        self._idx = 0
        self._first: list[ua.NodeId] = []  # the nodes of a file added through AddNodes, which the others copy
        self.manifest: Node | None = None

    async def build(self, server: Server, parent: Node, idx: int) -> None:
        self._server, self._idx = server, idx
        self._folder = await parent.add_folder(ua.NodeId("Files", idx), ua.QualifiedName("Files", idx))
        self.manifest = await self._folder.add_variable(ua.NodeId("Files.Manifest", idx),
                                                        ua.QualifiedName("Manifest", idx), "{}")
        text = ("what a console loads: JSON {station, language, tick_ms, parts: {part: path}, "
                "files: {path: sha256}}; each path is the FileType object Files.<path>")
        await self.manifest.write_attribute(ua.AttributeIds.Description,
                                            ua.DataValue(ua.Variant(ua.LocalizedText(text))))
        await self.refresh()

    async def run(self) -> None:
        """Look at the files every FILES_EVERY_S until cancelled."""
        while True:
            await asyncio.sleep(FILES_EVERY_S)
            try:
                await self.refresh()
            except Exception:  # the next look tries again; the files served stay as they were
                logger.exception("the station's files for consoles not refreshed")

    async def refresh(self) -> None:
        files = await asyncio.to_thread(scan, self.station, self.files)
        if files == self.files and self._nodes.keys() == files.keys():
            return
        assert self._server is not None and self._folder is not None and self.manifest is not None
        for rel in self._nodes.keys() - files.keys():
            await self._server.delete_nodes([self._nodes.pop(rel)], recursive=True)
        for rel, served in files.items():
            node = self._nodes.get(rel)
            if node is None:
                node = self._nodes[rel] = await self._add(rel)
            if self.files.get(rel) != served:
                await (await node.get_child("0:Size")).write_value(ua.Variant(len(served.content),
                                                                              ua.VariantType.UInt64))
        self.files = files
        await self.manifest.write_value(manifest_of(self.station, files))

    async def _add(self, rel: str) -> Node:
        """A FileType object as asyncua's `instantiate` makes it (every optional member too), from
        the type's declarations read once (condition_nodes.py): a tenth of the time; the first file
        through AddNodes, the others copies of its nodes while it is served (a start's files were
        two fifths of an OPC UA server's start through AddNodes each)."""
        assert self._server is not None and self._folder is not None
        server, idx = self._server, self._idx
        declared = await nodes.template(server, ua.ObjectIds.FileType, FILE_OPTIONAL)
        root = ua.NodeId(f"Files.{rel}", idx)
        ids = [root, *(ua.NodeId(".".join((root.Identifier, *d.path)), idx) for d in declared)]
        if self._first and self._first[0] in server.iserver.aspace:
            nodes.clone(server.iserver.aspace, self._first, ids, None, rel)
        else:
            item = ua.AddNodesItem(ParentNodeId=self._folder.nodeid, RequestedNewNodeId=root,
                                   ReferenceTypeId=ua.NodeId(ua.ObjectIds.Organizes),
                                   BrowseName=ua.QualifiedName(rel, idx), NodeClass=ua.NodeClass.Object,
                                   TypeDefinition=ua.NodeId(ua.ObjectIds.FileType))
            await _read_and_copy_attrs(server.get_node(ua.ObjectIds.FileType), ua.ObjectAttributes(), item)
            item.NodeAttributes.DisplayName = ua.LocalizedText(rel)
            await nodes.add_instance(server, item, ids, declared)
            self._first = ids
        for name, value in (("Writable", False), ("UserWritable", False)):
            await server.get_node(ua.NodeId(f"Files.{rel}.{name}", idx)).write_value(value)
        for name, call in (("Open", self._open), ("Read", self._read), ("Close", self._close),
                           ("GetPosition", self._position), ("SetPosition", self._seek)):
            server.link_method(server.get_node(ua.NodeId(f"Files.{rel}.{name}", idx)), call)
        return server.get_node(root)

    def _rel(self, parent: ua.NodeId) -> str:
        return str(parent.Identifier).removeprefix("Files.")

    async def _open(self, parent: ua.NodeId, mode: ua.Variant) -> Outputs:
        served = self.files.get(self._rel(parent))
        if served is None:
            return _bad(ua.StatusCodes.BadNotFound)
        if mode.Value != _READ_MODE:
            return _bad(ua.StatusCodes.BadNotWritable)
        handle = next(self._next)
        if len(self._handles) >= MAX_OPEN:
            del self._handles[next(iter(self._handles))]
        self._handles[handle] = [served.content, 0]
        return [ua.Variant(handle, ua.VariantType.UInt32)]

    async def _read(self, parent: ua.NodeId, handle: ua.Variant,
                    length: ua.Variant) -> Outputs:
        opened = self._handles.get(handle.Value)
        if opened is None or not isinstance(length.Value, int) or length.Value < 0:
            return _bad(ua.StatusCodes.BadInvalidArgument)
        content, position = opened
        chunk = content[position:position + length.Value]
        opened[1] = position + len(chunk)
        return [ua.Variant(chunk, ua.VariantType.ByteString)]

    async def _close(self, parent: ua.NodeId, handle: ua.Variant) -> Outputs:
        if self._handles.pop(handle.Value, None) is None:
            return _bad(ua.StatusCodes.BadInvalidArgument)
        return []

    async def _position(self, parent: ua.NodeId, handle: ua.Variant) -> Outputs:
        opened = self._handles.get(handle.Value)
        if opened is None:
            return _bad(ua.StatusCodes.BadInvalidArgument)
        return [ua.Variant(opened[1], ua.VariantType.UInt64)]

    async def _seek(self, parent: ua.NodeId, handle: ua.Variant,
                    position: ua.Variant) -> Outputs:
        opened = self._handles.get(handle.Value)
        if opened is None or not isinstance(position.Value, int):
            return _bad(ua.StatusCodes.BadInvalidArgument)
        opened[1] = min(position.Value, len(opened[0]))
        return []


def _bad(code: int) -> ua.CallMethodResult:
    result = ua.CallMethodResult()
    result.StatusCode = ua.StatusCode(code)
    return result
