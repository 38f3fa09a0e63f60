"""What a station's start built leaves the collector's walk once (app/station/heap.py): frozen after
the start of a headless station, once per process, and what is made afterwards is still collected."""

from __future__ import annotations

import gc
import weakref

import pytest

from app.cli import main
from app.station import heap
from tests.app.conftest import write_station


class Node:
    def __init__(self) -> None:
        self.me = self  # a reference cycle: only the collector frees it


@pytest.fixture
def unsettled(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(heap, "_settled", False)  # as in a process that has not started a station yet


def frozen(obj: object) -> bool:
    """In the permanent generation: tracked, but in none of the three a collection walks."""
    return gc.is_tracked(obj) and not any(o is obj for o in gc.get_objects())


def test_the_start_of_a_headless_station_freezes_what_it_built(tmp_path, unsettled) -> None:
    station = write_station(tmp_path / "st", 'NetPlcProgram = "p.stl"\n[modbus_server]\nenabled = false\n',
                            {"p.stl": "JMP 0\n"})
    alive = Node()  # made before the start, alive after it
    assert not frozen(alive)
    assert main(["--no-gui", str(station), "--duration", "0.1"]) == 0  # `main.py`, in this process
    assert heap._settled and frozen(alive)


def test_once_per_process_and_cycles_made_later_are_collected(unsettled) -> None:
    heap.settle()
    later = Node()
    heap.settle()  # a later start in the same process: nothing more is frozen
    assert not frozen(later)
    gone = weakref.ref(later)
    del later
    gc.collect()
    assert gone() is None
