"""Form behaviour on the engine thread: what the runtime adds to every scan by evaluating the forms.

A generated form of 300 acting elements (100 analog inputs with RegData and limit records, 100
discrete elements with RegMessages, 50 SyncGenerators, 50 SyncTimers), all bound to memory that
changes on every scan, is evaluated by `FormBehaviour` from each snapshot, as the runtime does
between two scans. Records go to a counting sink. Yardstick, in the same run: a bare loop that reads
the same 300 addresses from the same snapshots (the least any evaluation must do).

    python bench/behaviour.py [scans]
"""

from __future__ import annotations

import json
import statistics
import sys
import tempfile
import time
from pathlib import Path

from hmi_forms.behaviour import FormBehaviour
from hmi_forms.form import load_form
from netplc.memory import Memory, Snapshot
from netplc.records import Record

BATCH = 100


class CountingSink:
    def __init__(self) -> None:
        self.count = 0

    def put(self, record: Record) -> None:
        self.count += 1


def generate(folder: Path) -> Path:
    elements = []
    box = {"x": 0, "y": 0, "w": 10, "h": 10}
    for i in range(100):
        elements.append({"type": "AnalogBase", "Name": f"A{i}", **box, "InAddr": f"0{0o4000 + 2 * i:o}",
                         "Device": "Raw", "PhyLow": 10, "PhyHigh": 90, "Hysteresis": 1, "RegData": True,
                         "RegMessages": True})
    for i in range(100):
        elements.append({"type": "DiscreteBase", "Name": f"D{i}", **box, "InAddr": f"0{0o2000 + i:o}",
                         "TextFalse": "OFF", "TextTrue": "ON", "RegMessages": True})
    for i in range(50):
        elements.append({"type": "SyncGenerator", "Name": f"G{i}", **box, "InAddr": f"0{0o2200 + i:o}",
                         "OutAddr": f"0{0o2400 + i:o}", "Period0": 5, "Period1": 10, "Phase1": 1})
        elements.append({"type": "SyncTimer", "Name": f"T{i}", **box, "Ainput": f"0{0o2300 + i:o}",
                         "OutAddr": f"0{0o2500 + i:o}", "Period0": 4, "Phase0": 2})
    doc = {"form": {"title": "bench", "width": 100, "height": 100},
           "devices": [{"Name": "Raw", "AppMin": 0, "AppMax": 1000, "PhyMin": 0, "PhyMax": 100}],
           "elements": elements}
    path = folder / "behaviour.hmi"
    path.write_text(json.dumps(doc))
    return path


def snapshots(scans: int) -> list[Snapshot]:
    mem = Memory()
    out = []
    for s in range(scans):
        for i in range(100):
            mem.set_word(0o4000 + 2 * i, (s * 7 + i * 13) % 1001)
            mem.set_bit(0o2000 + i, (s + i) // 3 % 2)
        for i in range(50):
            mem.set_bit(0o2200 + i, (s + i) // 20 % 2)
            mem.set_bit(0o2300 + i, (s + i) // 30 % 2)
        out.append(mem.snapshot(s, s * 0.1, 1.8e9 + s * 0.1))
    return out


def bare(snap: Snapshot) -> int:
    total = 0
    for i in range(100):
        total += snap.get_word(0o4000 + 2 * i) + snap.get_bit(0o2000 + i)
    for i in range(50):
        total += snap.get_bit(0o2200 + i) + snap.get_bit(0o2300 + i)
    return total


def main() -> None:
    scans = int(sys.argv[1]) if len(sys.argv) > 1 else 5_000
    with tempfile.TemporaryDirectory() as tmp:
        form = load_form(generate(Path(tmp)))
    sink = CountingSink()
    behaviour = FormBehaviour([form], Memory(), sink)
    snaps = snapshots(scans)
    ours: list[float] = []
    yard: list[float] = []
    for start in range(0, scans, BATCH):  # batches alternate, so both see the same machine load
        batch = snaps[start:start + BATCH]
        t0 = time.perf_counter()
        for snap in batch:
            behaviour(snap)
        t1 = time.perf_counter()
        for snap in batch:
            bare(snap)
        t2 = time.perf_counter()
        ours.append((t1 - t0) / len(batch) * 1e6)
        yard.append((t2 - t1) / len(batch) * 1e6)
    mean, base = statistics.mean(ours), statistics.mean(yard)
    print(f"form behaviour, 300 acting elements changing every scan: {mean:.0f} us/scan mean, "
          f"{statistics.median(ours):.0f} us median, max batch {max(ours):.0f} us, {sink.count / scans:.0f} "
          f"records/scan (target <= 1000 us/scan)")
    print(f"yardstick, a bare loop reading the same 300 addresses: {base:.0f} us/scan: "
          f"behaviour = {mean / base:.1f}x the bare reads")


if __name__ == "__main__":
    main()
