"""The mirror's frames: whatever changed between two scans, the standby's image is the primary's
after every frame; a delta before the whole state, or a frame that lies, is refused."""

from __future__ import annotations

import random

import pytest

from app.station.mirror import Capture, Encoder, LinkError, Mirror
from netplc.forcing import Force
from netplc.memory import Memory
from netplc.records import Record


def test_every_frame_leaves_the_standby_with_the_primary_s_state() -> None:
    rng = random.Random(26)
    mem, encoder, mirror = Memory(), Encoder(), Mirror()
    for scan in range(200):
        for _ in range(rng.randint(0, 40)):
            if rng.random() < 0.3:
                mem.bits[rng.randrange(2048)] = rng.randint(0, 1)
            else:
                mem.data[rng.randrange(len(mem.data))] = rng.randrange(256)
        forces = (Force("bit", 0o2000, 1, "olga"),) if scan % 50 > 25 else ()
        snap = mem.snapshot(scan, state="running", forces=forces)
        mirror.apply(encoder.frame(Capture(snap, {0o3000: scan * 0.1}, {0o3010: scan}, 0)))
        assert bytes(mirror.image) == bytes(snap.bits) + snap.data
        assert (mirror.scan, mirror.tim, mirror.ctr, mirror.forces) == (scan, {0o3000: scan * 0.1},
                                                                        {0o3010: scan}, forces)


def test_a_delta_before_the_whole_state_is_refused() -> None:
    mem, encoder = Memory(), Encoder()
    encoder.frame(Capture(mem.snapshot(1), {}, {}, 0))
    with pytest.raises(LinkError, match="before the full state"):
        Mirror().apply(encoder.frame(Capture(mem.snapshot(2), {}, {}, 0)))
    with pytest.raises(LinkError, match="cannot be read"):
        Mirror().apply(b"\x00\x00\x00\x05{nope")


def test_alarm_states_reach_the_standby_once_however_frames_come() -> None:
    mem, encoder, mirror = Memory(), Encoder(), Mirror()
    acked = {"active": True, "acked": True, "acked_by": "ivan"}
    mirror.apply(encoder.frame(Capture(mem.snapshot(1), {}, {}, 0, {"TRIP.ALARM": acked})))
    mirror.apply(encoder.frame(Capture(mem.snapshot(2), {}, {}, 0, {"DOOR.ALARM": {"active": False}})))
    mirror.apply(encoder.frame(Capture(mem.snapshot(3), {}, {}, 0)))
    assert mirror.take_alarms() == {"TRIP.ALARM": acked, "DOOR.ALARM": {"active": False}}
    assert mirror.take_alarms() == {}


def test_the_standby_keeps_the_primary_s_records_until_it_says_they_are_on_its_disk() -> None:
    mem, encoder, mirror = Memory(), Encoder(), Mirror()
    raised = Record(1_790_000_000.25, "alarm", 2, 3, "TRIP.ALARM", 1, 1.0, "raised", pid=7 << 50)
    wrote = Record(1_790_000_000.3, "operator", source="ivan", number=0o4000, value=5, text="write",
                   pid=(7 << 50) + 1)
    mirror.apply(encoder.frame(Capture(mem.snapshot(1), {}, {}, 0, records=(raised,))))
    mirror.apply(encoder.frame(Capture(mem.snapshot(2), {}, {}, 0, records=(wrote,), committed=0)))
    assert (mirror.pending, mirror.last_pid) == ([(1, [raised]), (2, [wrote])], (7 << 50) + 1)
    mirror.apply(encoder.frame(Capture(mem.snapshot(3), {}, {}, 0, committed=1)))
    assert mirror.take_pending() == [wrote]  # what a takeover now archives, the same records
    assert mirror.take_pending() == []
