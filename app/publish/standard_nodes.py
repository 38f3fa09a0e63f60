"""The standard address space of OPC UA Part 5 for the station's OPC UA servers, from a cache file.

asyncua fills it (6,174 nodes) at every server's init by running its generated code through
AddNodes: 3 s of CPU, most of a station's start with OPC UA. Here the first start on a host fills
it as asyncua does and keeps every node pickled in one file of the user's cache (`cache_folder`),
named for the asyncua and Python versions (another version fills and writes its own); later starts
read that file (11 MB, a few ms) and unpickle a node when a server first reaches it: a station's
server reaches about 300 of them at its start, a client's browse reaches more as it goes.

The nodes so made are kept for the process, untouched, and every server gets nodes, attribute
records and reference lists of its own, copied from them at its first use of each (`_Nodes`), as
its own fill would give it: a process may run several servers (the tests do). The attribute values
themselves are shared: a server never changes a stored value in place (a write stores a new
DataValue), except that a caller may append to an array it read (`Server.register_namespace`
does), so array values are copied too.

The file is a pickle, which runs code as it loads: it is read only when this user owns it and no
one else may write it (the folder is made private), else the server fills as asyncua does.
"""

from __future__ import annotations

import contextlib
import copy
import logging
import marshal
import os
import pickle
import sys
import threading
from collections.abc import Iterator
from importlib.metadata import version
from pathlib import Path
from typing import Any

from asyncua import Server, ua
from asyncua.server.address_space import AddressSpace, AttributeValue, NodeData, NodeManagementService

logger = logging.getLogger(__name__)

CACHE_ENV = "NETPLC_CACHE_DIR"  # the cache folder instead of the user's (a read-only home, the tests)
FORMAT = 1  # of the file: bumped when what it holds changes

if os.name == "nt":  # not run by the suite (Linux); here so that a station starts on Windows too
    import _winapi
    import msvcrt

    @contextlib.contextmanager
    def _exclusive(path: Path) -> Iterator[None]:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            msvcrt.locking(fd, msvcrt.LK_LOCK, 1)  # retries for 10 s, then raises
            yield
        finally:
            os.close(fd)  # releases the lock

    def _private(path: Path) -> bool:
        return True  # the user's own profile: NTFS rights, not mode bits, keep others out

    def _running(pid: int) -> bool:
        try:
            handle = _winapi.OpenProcess(0x1000, False, pid)  # PROCESS_QUERY_LIMITED_INFORMATION
        except OSError as e:
            return e.winerror != 87  # ERROR_INVALID_PARAMETER: no such process (5, denied: it runs)
        try:
            return _winapi.GetExitCodeProcess(handle) == _winapi.STILL_ACTIVE
        finally:
            _winapi.CloseHandle(handle)
else:
    import fcntl

    @contextlib.contextmanager
    def _exclusive(path: Path) -> Iterator[None]:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o600)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
            yield
        finally:
            os.close(fd)  # releases the lock

    def _private(path: Path) -> bool:
        info = path.stat()
        return info.st_uid == os.getuid() and not info.st_mode & 0o022

    def _running(pid: int) -> bool:
        try:
            os.kill(pid, 0)  # no signal sent: asks whether the process exists
        except ProcessLookupError:
            return False
        except PermissionError:  # another user's process
            return True
        return True


def cache_folder() -> Path:
    """$NETPLC_CACHE_DIR, else the user's cache: $XDG_CACHE_HOME/netplc (~/.cache/netplc), on
    Windows %LOCALAPPDATA%\\netplc."""
    if os.environ.get(CACHE_ENV):
        return Path(os.environ[CACHE_ENV])
    if os.name == "nt":
        return Path(os.environ.get("LOCALAPPDATA") or Path.home() / "AppData" / "Local") / "netplc"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "netplc"


def cache_file(folder: Path) -> Path:
    return folder / (f"opcua-standard-{FORMAT}-asyncua-{version('asyncua')}-"
                     f"py{sys.version_info.major}{sys.version_info.minor}.nodes")


def fill() -> dict[ua.NodeId, NodeData]:
    """The standard address space as asyncua's own init fills it."""
    from asyncua.server.standard_address_space import standard_address_space

    aspace = AddressSpace()
    standard_address_space.fill_address_space(NodeManagementService(aspace))
    return aspace._nodes


class _Kept:
    """The process's standard nodes, untouched: each unpickled from the file at its first use, or
    all at once from a fill."""

    def __init__(self, blobs: dict[ua.NodeId, bytes], nodes: dict[ua.NodeId, NodeData]) -> None:
        self._blobs, self._nodes = blobs, nodes

    def __getitem__(self, nodeid: ua.NodeId) -> NodeData:
        node = self._nodes.get(nodeid)
        if node is None:
            node = self._nodes.setdefault(nodeid, pickle.loads(self._blobs[nodeid]))
        return node

    def __contains__(self, nodeid: object) -> bool:
        return nodeid in self._blobs or nodeid in self._nodes

    def __iter__(self) -> Iterator[ua.NodeId]:
        return iter(self._blobs or self._nodes)


def _write(path: Path, nodes: dict[ua.NodeId, NodeData]) -> None:
    records = []
    for nodeid, node in nodes.items():
        assert node.call is None and all(
            r.value_callback is None and r.value_setter is None and not r.datachange_callbacks
            for r in node.attributes.values()), f"{nodeid}: a callback in the standard address space"
        records.append((nodeid.Identifier, nodeid.NamespaceIndex, int(nodeid.NodeIdType),
                        pickle.dumps(node, pickle.HIGHEST_PROTOCOL)))
    path.parent.mkdir(mode=0o700, parents=True, exist_ok=True)
    part = path.with_name(f"{path.name}.{os.getpid()}.part")
    fd = os.open(part, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)  # the user's alone, whatever the umask
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(marshal.dumps(records))
        os.replace(part, path)  # whole or not at all
    finally:
        part.unlink(missing_ok=True)  # a write that failed (a full disk) leaves no part; a kill does


def _sweep(folder: Path) -> None:
    """Remove the parts of cache files whose writer no longer runs (killed, crashed, the power cut
    while it wrote: 11-18 MB each, never read, else left forever), logging each. The part of a
    running process stays: two stations of a host may write at once, each the file of its own
    asyncua under its own lock, and only a part's pid tells whether its writer is still at it."""
    for part in folder.glob("opcua-standard-*.part"):
        pid = part.name.rsplit(".", 2)[-2]
        if not pid.isdigit() or _running(int(pid)):
            continue
        try:
            part.unlink(missing_ok=True)  # missing: a start of another asyncua swept it first
        except OSError:
            logger.exception("%s: cannot remove this part of a cache file its process left", part)
            continue
        logger.info("%s removed: the part of a cache file left by process %s, which no longer runs",
                    part, pid)


def _read(path: Path) -> dict[ua.NodeId, bytes] | None:
    """The file's nodes, still pickled; None where there is none to be read (then one is made)."""
    if not path.exists():
        return None
    if not _private(path):
        logger.warning("%s: not read (others may write it); the OPC UA server fills the standard "
                       "address space itself", path)
        return None
    try:
        blobs = {ua.NodeId(ident, ns, ua.NodeIdType(kind)): blob
                 for ident, ns, kind, blob in marshal.loads(path.read_bytes())}
        first = pickle.loads(next(iter(blobs.values())))  # unpickles as the others will
        assert isinstance(first, NodeData), type(first)
    except Exception:  # damaged, or of another build of asyncua under the same version
        logger.exception("%s: not a cache of the standard address space: made again", path)
        return None
    return blobs


def _load(folder: Path) -> _Kept:
    path = cache_file(folder)
    blobs = _read(path)
    if blobs is not None:
        return _Kept(blobs, {})
    nodes = None
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        with _exclusive(path.with_name(f"{path.name}.lock")):  # one fill of the processes starting at once
            blobs = _read(path)
            if blobs is not None:
                return _Kept(blobs, {})
            _sweep(folder)
            nodes = fill()
            _write(path, nodes)
        logger.info("OPC UA standard address space cached in %s for the next starts", path)
    except OSError:
        logger.exception("%s: the standard address space is not cached: each start fills it", path)
    return _Kept({}, fill() if nodes is None else nodes)


_kept: dict[Path, _Kept] = {}
_loading = threading.Lock()


def kept(folder: Path | None = None) -> _Kept:
    """The process's standard nodes from the cache in `folder` (`cache_folder()`), loaded once."""
    folder = folder or cache_folder()
    with _loading:
        if folder not in _kept:
            _kept[folder] = _load(folder)
        return _kept[folder]


def _copy(nodeid: ua.NodeId, data: NodeData) -> NodeData:
    node = NodeData(nodeid)
    for attribute, record in data.attributes.items():
        value = record.value
        if value is not None and value.Value is not None and isinstance(value.Value.Value, list):
            value, variant = copy.copy(value), copy.copy(value.Value)
            variant.Value = list(variant.Value)
            value.Value = variant
        node.attributes[attribute] = AttributeValue(value)
    node.references = list(data.references)
    return node


class _Nodes(dict):
    """A server's nodes (`AddressSpace._nodes`): those it added, and the kept ones, each copied at
    its first use: most are never used. Every way asyncua reaches the nodes (index, get, in, del,
    keys, items, clear) sees both."""

    def __init__(self, first: _Kept) -> None:
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


def install(server: Server, folder: Path | None = None) -> None:
    """`server`'s init takes the standard address space from the cache in `folder`
    (`cache_folder()`) instead of filling it: call before `server.init()`."""
    iserver = server.iserver

    async def load_standard_address_space(shelf_file: Path | None = None) -> None:
        assert not iserver.aspace._nodes, "nodes added before the standard address space"
        iserver.aspace._nodes = _Nodes(kept(folder))

    iserver.load_standard_address_space = load_standard_address_space  # type: ignore[method-assign]
