import sys
import threading
import zlib

from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink
from registrar.retain import HEADER, MAGIC, VERSION, Retainer, read_save

PROGRAM = "TNA $02000\nCTR C:$03000 N:100\nJMP 0\n"


def engine() -> Engine:
    return Engine(parse(PROGRAM), clock=FakeClock(), wallclock=lambda: 1_790_000_000.0, sink=ListSink())


def filled(value: int) -> Engine:
    e = engine()
    e.mem.set_word(0o4000, value)
    e.mem.set_word(0o77776, value + 1)  # the last word of the last bank
    e.mem.set_bit(0o3000 + 5, 1)
    e.mem.set_bit(0o3477, 1)
    e.mem.set_bit(0o2001, 1)  # not retentive
    e.tim_ticks[0o2200] = 12.5
    e.ctr_values[0o3000] = value % 100
    e.scan()
    return e


def texts(e: Engine) -> list[str]:
    return [r.text or "" for r in e.sink.records if r.kind == "system"]


def test_save_and_restore_the_current_save(tmp_path):
    path = tmp_path / "retain.bin"
    Retainer(path, filled(1234)).save()
    e = engine()
    assert Retainer(path, e).restore() == "current"
    assert e.mem.get_word(0o4000) == 1234 and e.mem.get_word(0o77776) == 1235
    assert e.mem.get_bit(0o3005) == 1 and e.mem.get_bit(0o3477) == 1
    assert e.mem.get_bit(0o2001) == 0
    assert e.held_values()[0] == {0o2200: 12.5}
    assert e.ctr_values[0o3000] == 34
    assert e.snapshot.get_word(0o4000) == 1234  # published before the first scan
    assert texts(e) == ["retentive memory restored from the current save retain.bin"]


def test_a_damaged_current_save_falls_back_to_the_previous(tmp_path):
    path = tmp_path / "retain.bin"
    r = Retainer(path, filled(1))
    r.save()
    r.engine.mem.set_word(0o4000, 2)
    r.engine.scan()
    r.save()
    assert read_save(r.previous).data[0] == 1 and read_save(path).data[0] == 2
    blob = bytearray(path.read_bytes())
    blob[100] ^= 0xFF
    path.write_bytes(bytes(blob))
    e = engine()
    restored = Retainer(path, e)
    assert restored.restore() == "previous"
    assert e.mem.get_word(0o4000) == 1
    assert "damaged" in texts(e)[0] and "previous save" in texts(e)[0]
    assert "writes acknowledged after 2026-" in texts(e)[0] and texts(e)[0].endswith(" may be lost")
    restored.save()  # the damaged current file must not push the good previous one out
    assert read_save(restored.previous).data[0] == 1 and read_save(path).data[0] == 1


def test_a_truncated_save_and_a_missing_previous_give_zeroes(tmp_path):
    path = tmp_path / "retain.bin"
    Retainer(path, filled(7)).save()
    path.write_bytes(path.read_bytes()[:1000])
    e = engine()
    e.mem.set_word(0o4000, 99)
    assert Retainer(path, e).restore() == "zeroes"
    assert e.mem.get_word(0o4000) == 0 and e.held_values() == ({}, {})
    assert texts(e) == ["retentive memory starts from zeroes "
                        "(current save is damaged (length or checksum wrong); previous save is missing): "
                        "every write acknowledged before may be lost"]


def test_a_save_naming_a_timer_outside_the_io_bits_falls_back(tmp_path):
    path = tmp_path / "retain.bin"
    r = Retainer(path, filled(3))
    r.save()
    r.save()  # the same state as the previous save too
    payload = path.read_bytes()[HEADER.size:].replace(b'"1152": 12.5', b'"4096": 12.5')
    path.write_bytes(HEADER.pack(MAGIC, VERSION, zlib.crc32(payload), len(payload)) + payload)
    e = engine()
    assert Retainer(path, e).restore() == "previous"
    assert "outside the I/O bits" in texts(e)[0]
    assert e.held_values() == ({0o2200: 12.5}, {0o3000: 3})


def test_first_start_without_any_save(tmp_path):
    e = engine()
    assert Retainer(tmp_path / "none" / "retain.bin", e).restore() == "zeroes"
    assert "current save is missing" in texts(e)[0]


def test_stop_makes_a_final_save_and_failures_are_journaled(tmp_path):
    e = filled(55)
    r = Retainer(tmp_path / "retain.bin", e)
    r.start(interval=60.0)
    r.stop()
    assert r.saves == 1 and read_save(r.path).data[0] == 55
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    bad = Retainer(blocked / "retain.bin", e)
    answered: list[str] = []
    bad.after_save(lambda: answered.append("write"))
    bad.stop()
    bad.stop()
    assert answered == ["write"]  # applied and journaled: answered although the save failed
    assert bad.last_error and texts(e).count(texts(e)[-1]) == 1
    assert texts(e)[-1].startswith("retentive memory could not be saved")


# A timer that restarts when done (ticking once a scan: 0.01 s base, 0.01 s scans) beside a word
# that counts scans: in a consistent save the two agree as they do between any two scans.
TICKING = ("TFA $03001\nTIM C:$03000 N:7\nTNA $03760\nFON C:$02001 N:INCW S:$04002 D:$04000\n"
           "JMP 0\n")
SCANS = 20_000


def ticking() -> tuple[Engine, FakeClock]:
    clock = FakeClock()
    e = Engine(parse(TICKING), clock=clock, wallclock=lambda: 1_790_000_000.0, sink=ListSink())
    e.mem.set_bit(0o3773, 0)  # time base 0.01 s
    return e, clock


def test_a_save_takes_memory_and_timer_values_of_the_same_moment(tmp_path):
    e, clock = ticking()
    stop = threading.Event()

    def scanning() -> None:
        while not stop.is_set():
            clock.advance(0.01)
            e.scan()

    path = tmp_path / "retain.bin"
    r = Retainer(path, e)
    r.start(interval=60.0)
    thread = threading.Thread(target=scanning)
    interval = sys.getswitchinterval()
    sys.setswitchinterval(1e-5)  # threads change hands within scans and within a save's reads
    thread.start()
    saved = []
    try:
        while len(saved) < 30 and e.scan_counter < SCANS - 1_000:
            done = threading.Event()
            r.after_save(done.set)
            assert done.wait(10)
            s = read_save(path)
            saved.append((int.from_bytes(s.data[:2], "little"), round(s.tim.get(0o3000, 0.0), 6)))
    finally:
        stop.set()
        thread.join()
        sys.setswitchinterval(interval)
        r.stop()
    # the pairs the two take between scans, over the scans the saves were taken in (not all SCANS)
    reference, clock = ticking()
    agree = set()
    while reference.scan_counter < e.scan_counter:
        clock.advance(0.01)
        reference.scan()
        agree.add((reference.mem.get_word(0o4000), round(reference.tim_ticks[0o3000], 6)))
    assert len(saved) >= 3 and set(saved) <= agree


class SavingSink(ListSink):
    """The station's sink in small (app/station/runtime.py): a record is kept at once, and a writer is
    answered once the memory of the scan that applied its write is saved."""

    def __init__(self) -> None:
        super().__init__()
        self.retainer: Retainer | None = None

    def after_commit(self, callback) -> None:
        assert self.retainer is not None
        self.retainer.after_save(callback)


def saving(tmp_path) -> tuple[Engine, Retainer]:
    sink = SavingSink()
    e = Engine(parse(PROGRAM), clock=FakeClock(), wallclock=lambda: 1_790_000_000.0, sink=sink)
    sink.retainer = Retainer(tmp_path / "retain.bin", e)
    return e, sink.retainer


def test_the_writers_of_a_scan_are_answered_by_one_save_that_holds_their_writes(tmp_path):
    e, r = saving(tmp_path)
    r.start(interval=60.0)
    try:
        answers: list[tuple[int, bool, int]] = []  # (write, ok, its word in the save when answered)
        all_done = threading.Event()

        def answer(i: int):
            def done(ok: bool) -> None:
                answers.append((i, ok, int.from_bytes(read_save(r.path).data[2 * i : 2 * i + 2], "little")))
                if len(answers) == 100:
                    all_done.set()
            return done

        for i in range(100):
            assert e.write_word(0o4000 + 2 * i, 1000 + i, user="modbus test", done=answer(i))
        e.scan()
        assert all_done.wait(10)
        assert sorted(answers) == [(i, True, 1000 + i) for i in range(100)]
        assert r.saves == 1
    finally:
        r.stop()


def test_saves_wanted_while_the_disk_is_slow_are_one_save_of_the_newest_scan(tmp_path):
    e, r = saving(tmp_path)
    r.start(interval=60.0)
    answered = threading.Semaphore(0)
    try:
        with r._lock:  # a slow disk: the first save waits for it
            for value in (1, 2, 3, 4):
                e.write_word(0o4000, value, user="modbus test", done=lambda ok: answered.release())
                e.scan()
        for _ in range(4):
            assert answered.acquire(timeout=10)
        # the first scan's save (if the saver took it before the next scan), then one save of the
        # newest scan for the states taken meanwhile: never a save per scan queued behind the disk
        assert r.saves <= 2 and read_save(r.path).data[:2] == (4).to_bytes(2, "little")
    finally:
        r.stop()


def test_a_save_written_when_the_station_was_killed_is_used_and_becomes_current(tmp_path):
    path = tmp_path / "retain.bin"
    r = Retainer(path, filled(1))
    for value in (2, 3):
        r.save()
        r.engine.mem.set_word(0o4000, value)
        r.engine.scan()
    r.save()
    path.replace(r._tmp)  # killed between the save's two renames: current moved to .prev, .tmp complete
    e = engine()
    restored = Retainer(path, e)
    assert restored.restore() == "current"
    assert e.mem.get_word(0o4000) == 3
    assert texts(e) == ["retentive memory restored from the save written at the crash, retain.bin.tmp "
                        "(current save is missing)"]
    assert read_save(path).data[:2] == (3).to_bytes(2, "little") and not restored._tmp.exists()
    restored.save()  # the save used keeps its place as the previous one
    assert read_save(restored.previous).data[:2] == (3).to_bytes(2, "little")
