"""The standard address space from the cache (app/publish/standard_nodes.py) is asyncua's own fill."""

from __future__ import annotations

import logging
import os
from pathlib import Path

import pytest
from asyncua import ua
from asyncua.server.address_space import NodeData

from app.publish import standard_nodes
from tests.collection_paused import collection_paused  # noqa: F401  a fixture
from tests.opcua_address_space import fill_once


def same_node(ours: NodeData, plain: NodeData) -> None:
    assert ours.nodeid == plain.nodeid and ours.call is None and plain.call is None
    assert ours.attributes.keys() == plain.attributes.keys(), ours.nodeid
    for attribute, record in plain.attributes.items():
        copied = ours.attributes[attribute]
        assert copied.value == record.value, (ours.nodeid, attribute)
        assert copied.value_callback is copied.value_setter is None and not copied.datachange_callbacks
    assert ours.references == plain.references, ours.nodeid


@pytest.mark.usefixtures("collection_paused")
def test_a_server_gets_from_the_cache_every_node_attribute_and_reference_of_a_plain_fill() -> None:
    """The run's cache file (made by the first start that found none), read as a later start reads
    it, gives a server the nodes of asyncua's plain fill: the same NodeIds, and for each the same
    attributes with the same values and no callbacks, and the same references in the same order.
    The suite's dearest test (4 s of CPU: a plain fill, every node unpickled; without the cyclic
    collector, which walked the growing heap for 1.5 s more) and its proof that every server of
    every other test has the standard address space; where this process made the run's cache, its
    fill, untouched (servers copy from it), is the plain fill compared."""
    fill_once()
    kept = standard_nodes._load(standard_nodes.cache_folder())  # from the file, as a station's next start
    assert kept._blobs, "the cache was read from its file"
    aspace = standard_nodes._Nodes(kept)
    ours = standard_nodes.kept()
    plain = standard_nodes.fill() if ours._blobs else ours._nodes
    assert set(aspace.keys()) == set(plain) and len(aspace) == len(plain) > 6000
    for nodeid, node in plain.items():
        same_node(aspace[nodeid], node)


def test_each_server_has_nodes_of_its_own() -> None:
    """What one server changes of a standard node (a value appended to an array it read, a
    reference, a deleted node) another server of the process does not see, and the kept node
    stays as it was."""
    fill_once()
    one, other = (standard_nodes._Nodes(standard_nodes.kept()) for _ in range(2))
    array = ua.NodeId(ua.ObjectIds.ServerState_EnumStrings)
    one[array].attributes[ua.AttributeIds.Value].value.Value.Value.append(ua.LocalizedText("Odd"))
    server = ua.NodeId(ua.ObjectIds.Server)
    one[server].references.append(one[server].references[0])
    del one[ua.NodeId(ua.ObjectIds.Server_ServerRedundancy)]
    for nodes in (other, standard_nodes.kept()):
        assert len(nodes[array].attributes[ua.AttributeIds.Value].value.Value.Value) == 8
    assert len(other[server].references) == len(standard_nodes.kept()[server].references) \
        == len(one[server].references) - 1
    assert ua.NodeId(ua.ObjectIds.Server_ServerRedundancy) in other
    assert ua.NodeId(ua.ObjectIds.Server_ServerRedundancy) not in one
    assert ua.NodeId(ua.ObjectIds.Server_ServerRedundancy) not in list(one)


@pytest.fixture
def some_nodes(monkeypatch: pytest.MonkeyPatch) -> dict[ua.NodeId, NodeData]:
    """A start's fill is 50 nodes of the standard address space (asyncua's whole fill is 3 s
    of CPU: what a cache file holds is the same for 50 nodes as for 6,174)."""
    fill_once()
    kept = standard_nodes.kept()
    nodes = {nodeid: kept[nodeid] for nodeid in list(kept)[:50]}
    monkeypatch.setattr(standard_nodes, "fill", lambda: dict(nodes))
    return nodes


def test_the_first_start_writes_the_cache_and_the_next_reads_it(
        tmp_path: Path, some_nodes: dict[ua.NodeId, NodeData], monkeypatch: pytest.MonkeyPatch) -> None:
    """A start that finds no cache fills as asyncua does and writes what it filled, whole (a file
    replaced, never half written: no part left), the user's alone whatever the umask, in a folder
    of the user's alone; the next start reads the nodes back from it. $NETPLC_CACHE_DIR names the
    folder."""
    folder = tmp_path / "cache"
    monkeypatch.setenv(standard_nodes.CACHE_ENV, str(folder))
    assert standard_nodes.cache_folder() == folder
    first = standard_nodes._load(folder)
    assert not first._blobs and list(first) == list(some_nodes)
    assert folder.stat().st_mode & 0o777 == 0o700
    assert standard_nodes.cache_file(folder).stat().st_mode & 0o777 == 0o600
    made = [p.name for p in folder.iterdir() if p.suffix != ".lock"]
    assert made == [standard_nodes.cache_file(folder).name]
    monkeypatch.setattr(standard_nodes, "fill", lambda: pytest.fail("filled again"))
    second = standard_nodes._load(folder)
    assert list(second._blobs) == list(some_nodes)
    for nodeid, node in some_nodes.items():
        same_node(second[nodeid], node)


def test_a_cache_others_may_write_is_not_read(
        tmp_path: Path, some_nodes: dict[ua.NodeId, NodeData], caplog: pytest.LogCaptureFixture) -> None:
    """A pickle runs code as it loads: a cache file that others may write is filled over with a
    warning, never read."""
    standard_nodes._load(tmp_path)
    path = standard_nodes.cache_file(tmp_path)
    os.chmod(path, 0o666)
    with caplog.at_level(logging.WARNING, standard_nodes.__name__):
        again = standard_nodes._load(tmp_path)
    assert not again._blobs and list(again) == list(some_nodes)
    assert f"{path}: not read (others may write it)" in caplog.text


def test_a_start_that_cannot_write_the_cache_fills_and_says_so(
        tmp_path: Path, some_nodes: dict[ua.NodeId, NodeData], caplog: pytest.LogCaptureFixture) -> None:
    """No cache folder to be made (a read-only home): the server fills as asyncua does, and the
    log says why each start does."""
    folder = tmp_path / "not a folder"
    folder.write_text("")
    with caplog.at_level(logging.ERROR, standard_nodes.__name__):
        kept = standard_nodes._load(folder)
    assert list(kept) == list(some_nodes)
    assert "the standard address space is not cached: each start fills it" in caplog.text


def test_a_damaged_cache_is_made_again(
        tmp_path: Path, some_nodes: dict[ua.NodeId, NodeData], caplog: pytest.LogCaptureFixture) -> None:
    """A cache file cut short (a full disk) or of another build of asyncua is not a server's
    address space: the start says so, fills and writes it again."""
    standard_nodes._load(tmp_path)
    path = standard_nodes.cache_file(tmp_path)
    path.write_bytes(path.read_bytes()[:5000])
    with caplog.at_level(logging.ERROR, standard_nodes.__name__):
        again = standard_nodes._load(tmp_path)
    assert not again._blobs and list(again) == list(some_nodes)
    assert f"{path}: not a cache of the standard address space: made again" in caplog.text
    assert list(standard_nodes._load(tmp_path)._blobs) == list(some_nodes)
