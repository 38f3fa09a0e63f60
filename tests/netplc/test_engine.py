"""The engine: logic instructions (docs/architecture.md section 4), jumps, run states, special bits,
FON dispatch, queued writes and scan statistics; every behaviour under both the compiled engine and
the reference interpreter."""

from __future__ import annotations

import itertools
import logging

import pytest

from netplc import backend
from netplc.address import EMERGENCY_STOP, FERR1, GEN_BASE, TIMEBASE_HI, TIMEBASE_LO
from netplc.engine import RunState
from netplc.functions.registry import REGISTRY, FunctionSpec
from tests.netplc.test_core_support import BOTH, ENGINE_IDS, Rig, with_fon

engines = pytest.mark.parametrize("compiled", BOTH, ids=ENGINE_IDS)

A, B, C, D = 0o0, 0o1, 0o2, 0o2000

FIGURES = {
    # manual Fig. 2.2.1-2.2.3 as the spec digest compiles them, with the function each draws
    "2.2.1 (!a)*b*c": ("TFA $0\nTNA $1\nTNA $2\nYON $02000", lambda a, b, c: (not a) and b and c),
    "2.2.2 (!a)+b+c": ("TFA $0\nTNO $1\nTNO $2\nYON $02000", lambda a, b, c: (not a) or b or c),
    "2.2.3 (!a)*b+c": ("TFA $0\nTNA $1\nTNE $2\nYON $02000", lambda a, b, c: ((not a) and b) or c),
}


@engines
@pytest.mark.parametrize("figure", list(FIGURES))
def test_figure_chains_over_every_input_combination(compiled, figure):
    text, expected = FIGURES[figure]
    rig = Rig(text, compiled)
    for a, b, c in itertools.product((0, 1), repeat=3):
        rig.step(b00000=a, b00001=b, b00002=c)
        assert rig.bit(D) == int(bool(expected(a, b, c))), (a, b, c)


@engines
def test_series_of_parallel_branches_with_tne(compiled):
    # a*b + c*d: TNE closes the branch a*b and starts c*d (docs/architecture.md section 4)
    rig = Rig("TNA $0\nTNA $1\nTNE $2\nTNA $3\nYON $02000", compiled)
    for a, b, c, d in itertools.product((0, 1), repeat=4):
        rig.step(b0=a, b1=b, b2=c, b3=d)
        assert rig.bit(D) == int((a and b) or (c and d))


@engines
def test_tfo_and_tfe_use_the_inverted_contact(compiled):
    rig = Rig("TNA $0\nTFO $1\nYON $02000\nTNA $0\nTFE $1\nYON $02001", compiled)
    for a, b in itertools.product((0, 1), repeat=2):
        rig.step(b0=a, b1=b)
        assert rig.bit(0o2000) == int(a or not b)
        assert rig.bit(0o2001) == int(a or not b)


@engines
def test_a_chain_without_contacts_switches_its_coil_on(compiled):
    rig = Rig("YON $02000\nNOP\nYON $02001", compiled)
    rig.step()
    assert rig.bit(0o2000) == rig.bit(0o2001) == 1


@engines
def test_son_and_sof_latch_only_when_the_chain_is_true(compiled):
    rig = Rig("TNA $0\nSON $02000\nTNA $1\nSOF $02000", compiled)
    rig.step(b0=1)
    assert rig.bit(0o2000) == 1
    rig.step(b0=0)
    assert rig.bit(0o2000) == 1  # latched
    rig.step(b1=1)
    assert rig.bit(0o2000) == 0
    rig.step(b1=0)
    assert rig.bit(0o2000) == 0


@engines
@pytest.mark.parametrize("op, taken_when", [("JMY", 1), ("JMN", 0)])
def test_conditional_jumps(compiled, op, taken_when):
    rig = Rig(f"TNA $0\n{op} over\nYON $02000\nover: YON $02001", compiled)
    for x in (0, 1):
        rig.bits[0o2000] = 0
        rig.step(b0=x)
        assert rig.bit(0o2000) == (0 if x == taken_when else 1)
        assert rig.bit(0o2001) == 1  # the chain after the label starts fresh (ACC = 1)


@engines
def test_jmp_skips_forward_and_jmp_0_ends_the_scan(compiled):
    rig = Rig("JMP l1\nYON $02000\nl1: YON $02001\nJMP 0\nYON $02002", compiled)
    rig.step()
    assert (rig.bit(0o2000), rig.bit(0o2001), rig.bit(0o2002)) == (0, 1, 0)


@engines
def test_backward_jump_loops_within_one_scan(compiled):
    # runs the counting chain twice per scan: the loop bit 02010 stops the second pass
    program = """
    again: TNA $00000
           CTR $03000 N:10
           TFA $00000
           YON $00000         ; toggles the counted input: a rising edge on every other pass
           TNA $02010
           JMY done
           SON $02010
           JMP again
    done:  TNA $03760
           SOF $02010
    """
    rig = Rig(program, compiled)
    rig.step()
    assert rig.engine.ctr_values[0o3000] == 1  # pass 1: input 0 -> no edge; pass 2: 1 -> edge
    rig.step()
    assert rig.engine.ctr_values[0o3000] == 2
    assert rig.engine.state is RunState.RUNNING


@engines
def test_skp_skips_the_next_instruction_when_the_chain_is_false(compiled):
    rig = Rig("TNA $0\nSKP\nYON $02000\nYON $02001", compiled)
    rig.step(b0=0)
    assert (rig.bit(0o2000), rig.bit(0o2001)) == (0, 1)
    rig.step(b0=1)
    assert (rig.bit(0o2000), rig.bit(0o2001)) == (1, 1)


@engines
def test_skp_skips_a_whole_fon_timer_or_jump(compiled):
    text = """
    TNA $0
    SKP
    TIM $03000 N:1
    TNA $0
    SKP
    FON?
    TNA $0
    SKP
    JMP end
    YON $02000
    end: YON $02001
    """
    rig = Rig(with_fon(text, 4242), compiled)
    rig.bits[0o3000] = 1  # skipped TIM must not touch its coil
    rig.step(b0=0)
    assert rig.bit(0o3000) == 1 and rig.bit(0o3010) == 0 and rig.bit(FERR1) == 0
    assert rig.bit(0o2000) == 1 and rig.bit(0o2001) == 1
    rig.bits[0o2000] = 0
    rig.step(b0=1)
    # the TIM ran with RES = 1 (a fresh chain after SKP), the FON set FErr1, the jump was taken
    assert rig.bit(0o3010) == 1 and rig.bit(FERR1) == 1
    assert rig.bit(0o2000) == 0 and rig.bit(0o2001) == 1


@engines
@pytest.mark.parametrize("first", [0, 1])
def test_skp_after_skp_and_skp_before_a_label(compiled, first):
    # a skipped SKP, and a SKP whose next instruction is a jump target (starts a new block)
    text = "TNA $0\nSKP\nSKP\nYON $02000\nTNA $1\nJMY l\nTNA $0\nSKP\nl: YON $02001\nYON $02002"
    rig = Rig(text, compiled)
    rig.step(b0=first, b1=0)
    assert rig.bit(0o2000) == 1
    assert rig.bit(0o2001) == first  # skipped when the chain is 0; else YON with a fresh chain = 1
    assert rig.bit(0o2002) == 1
    rig.step(b0=first, b1=1)
    assert rig.bit(0o2001) == 1  # the jump lands on the YON with ACC = 1


@engines
def test_hlt_halts_and_start_resumes(compiled):
    rig = Rig("TNA $03760\nCTR $03000 N:255\nTNA $0\nJMN go\nHLT\ngo: YON $02000", compiled)
    rig.step(b0=1)
    assert rig.engine.state is RunState.HALTED and rig.engine.state_text == "halted"
    assert rig.engine.snapshot.state == "halted"
    rig.step(b0=0)
    assert rig.bit(0o2000) == 0  # a halted engine runs no program
    assert rig.engine.scan_counter == 2  # but keeps publishing snapshots
    rig.engine.start()
    rig.step()
    assert rig.bit(0o2000) == 1 and rig.engine.state is RunState.RUNNING


@engines
def test_emergency_stop_bit_stops_with_code_11(compiled):
    rig = Rig("TNA $0\nSON $03770\nTNA $03760\nYON $02000", compiled)
    rig.step()
    assert rig.engine.state_text == "running" and rig.bit(0o2000) == 1
    rig.bits[0o2000] = 0
    rig.step(b0=1)  # the program itself raises the stop bit: the scan ends stopped
    assert rig.engine.state_text == "stopped, code 11"
    assert rig.engine.snapshot.state == "stopped, code 11"
    rig.bits[0o2000] = 0
    rig.step(b0=0)
    assert rig.bit(0o2000) == 0  # nothing runs while stopped
    rig.engine.start()
    assert rig.bit(EMERGENCY_STOP) == 0
    rig.step()
    assert rig.engine.state_text == "running" and rig.bit(0o2000) == 1


@engines
def test_emergency_stop_set_from_outside_stops_before_the_program(compiled):
    rig = Rig("YON $02000", compiled)
    rig.engine.write_bit(EMERGENCY_STOP, 1)
    rig.step()
    assert rig.engine.state_text == "stopped, code 11"
    assert rig.bit(0o2000) == 0


@engines
def test_watchdog_stops_an_endless_loop(compiled, monkeypatch):
    monkeypatch.setattr(backend, "WATCHDOG_STEPS", 1000)
    rig = Rig("YON $02000\nl: NOP\nJMP l", compiled)
    rig.step()
    assert rig.engine.state is RunState.STOPPED
    assert any("watchdog" in (r.text or "") for r in rig.sink.records)


@engines
def test_always_one_and_generators_follow_the_clock(compiled):
    rig = Rig("NOP", compiled)
    dt = 0.01
    history = []
    t = 0.0
    for _ in range(int(26.0 / dt)):
        rig.step(dt)
        t += dt
        history.append((t, [rig.bit(GEN_BASE + k) for k in range(8)]))
        assert rig.bit(0o3760) == 1
    for k in range(8):
        half = 0.05 * 2**k  # period 0.1 s * 2**k, 50 % duty
        edges = [t for (t, now), (_, before) in zip(history[1:], history) if now[k] != before[k]]
        assert len(edges) >= 2
        gaps = [b - a for a, b in itertools.pairwise(edges)]
        assert all(abs(g - half) < dt + 1e-9 for g in gaps), (k, gaps[:5])
        assert abs(edges[0] - half) < dt + 1e-9  # starts low, first rises after half a period


TIME_BASE_CASES = [(0, 0, 0.01), (1, 0, 0.1), (0, 1, 1.0), (1, 1, 10.0)]


@engines
@pytest.mark.parametrize("lo, hi, base", TIME_BASE_CASES, ids=["0.01s", "0.1s", "1s", "10s"])
@pytest.mark.parametrize("n", [0, 1, 7])
def test_timer_with_preset_n_finishes_after_n_ticks(compiled, lo, hi, base, n):
    rig = Rig(f"TNA $0\nTIM $03000 N:{n}", compiled)
    rig.bits[TIMEBASE_LO], rig.bits[TIMEBASE_HI] = lo, hi
    sub = 4  # scans per tick
    rig.step(base / sub, b0=1)  # the timer starts on this scan
    assert rig.bit(0o3000) == 1
    scans = 0
    while not rig.bit(0o3001):
        rig.step(base / sub)
        scans += 1
        assert scans <= n * sub
    assert scans == n * sub
    assert rig.engine.tim_ticks[0o3000] == pytest.approx(n)
    rig.step(base / sub, b0=0)
    assert rig.bit(0o3000) == rig.bit(0o3001) == 0 and rig.engine.tim_ticks[0o3000] == 0


@engines
def test_time_base_defaults_to_0_1_s(compiled):
    rig = Rig("TNA $0\nTIM $03000 N:3", compiled)
    assert (rig.bit(TIMEBASE_LO), rig.bit(TIMEBASE_HI)) == (1, 0)
    rig.step(0.1, b0=1)
    rig.step(0.1, scans=2)
    assert rig.bit(0o3001) == 0
    rig.step(0.1)
    assert rig.bit(0o3001) == 1


@engines
def test_counter_counts_rising_edges_up_to_n_and_resets(compiled):
    rig = Rig("TNA $0\nCTR $03000 N:3\nTNA $1\nYON $03001", compiled)
    for _ in range(2):
        rig.step(b0=1)
        rig.step(b0=1)  # held: no new edge
        rig.step(b0=0)
    assert rig.engine.ctr_values[0o3000] == 2 and rig.bit(0o3002) == 0
    for _ in range(3):
        rig.step(b0=1)
        rig.step(b0=0)
    assert rig.engine.ctr_values[0o3000] == 3 and rig.bit(0o3002) == 1  # saturates at N
    rig.step(b1=1)
    rig.step(b1=0)
    assert rig.engine.ctr_values[0o3000] == 0 and rig.bit(0o3002) == 0


# --- FON dispatch -----------------------------------------------------------------------------


FON_CHAIN = "TNA $0\nFON?\nTNA $03760\nYON $02000"  # FON at line 2, then a chain that must still run


@engines
def test_fon_of_a_function_not_in_the_registry_sets_ferr1(compiled):
    assert 4242 not in REGISTRY
    rig = Rig(with_fon(FON_CHAIN, 4242), compiled)
    rig.step(b0=0)
    assert rig.bit(FERR1) == 0 and rig.bit(0o3010) == 0
    rig.step(b0=1)
    assert rig.bit(FERR1) == 1 and rig.bit(0o3010) == 1
    assert rig.bit(0o2000) == 1  # the scan went on
    rig.bits[FERR1] = 0
    rig.step(b0=0)
    assert rig.bit(FERR1) == 0  # sticky: set only when the FON runs; cleared by the program


@engines
def test_fon_of_a_registered_number_removed_from_the_registry_sets_ferr1(compiled, monkeypatch):
    monkeypatch.setitem(REGISTRY, 4243, FunctionSpec(4243, "GONE", "M", "M", None, lambda ctx, fon: None))
    monkeypatch.delitem(REGISTRY, 4243)
    rig = Rig(with_fon(FON_CHAIN, 4243), compiled)
    rig.step(b0=1)
    assert rig.bit(FERR1) == 1


@engines
def test_fon_runs_every_scan_while_its_chain_is_true(compiled, monkeypatch):
    calls = []

    def run(ctx, fon):
        calls.append((ctx.scan_counter, fon.s, fon.d))
        ctx.mem.set_word(fon.d, ctx.mem.get_word(fon.s) + 1)

    monkeypatch.setitem(REGISTRY, 4244, FunctionSpec(4244, "PROBE", "M", "M", None, run))
    rig = Rig(with_fon(FON_CHAIN, 4244), compiled)
    rig.engine.mem.set_word(0o4000, 41)
    rig.step(b0=1, scans=3)
    rig.step(b0=0, scans=2)
    assert [c[0] for c in calls] == [0, 1, 2]
    assert calls[0][1:] == (0o4000, 0o4002)
    assert rig.engine.mem.get_word(0o4002) == 42
    assert rig.bit(FERR1) == 0


@engines
def test_fon_that_raises_sets_ferr1_reports_once_and_the_scan_goes_on(compiled, monkeypatch):
    def boom(ctx, fon):
        raise ZeroDivisionError("division by zero")

    monkeypatch.setitem(REGISTRY, 4245, FunctionSpec(4245, "BOOM", "M", "M", None, boom))
    rig = Rig(with_fon(FON_CHAIN, 4245), compiled)
    rig.step(b0=1, scans=3)
    assert rig.bit(FERR1) == 1 and rig.bit(0o2000) == 1
    faults = [r for r in rig.sink.records if r.kind == "system"]
    assert len(faults) == 1
    assert "BOOM" in faults[0].text and "line 2" in faults[0].text and "ZeroDivisionError" in faults[0].text
    rig.engine.load(rig.engine.program)  # a reload reports again: indices may mean other FONs now
    rig.step(b0=1)
    assert len([r for r in rig.sink.records if r.kind == "system"]) == 2


@engines
def test_hardware_module_function_only_sets_ferr1(compiled, monkeypatch):
    called = []
    spec = FunctionSpec(4246, "MODULE", "M", "M", None, lambda ctx, fon: called.append(1), hardware=True)
    monkeypatch.setitem(REGISTRY, 4246, spec)
    rig = Rig(with_fon(FON_CHAIN, 4246), compiled)
    rig.step(b0=1)
    assert rig.bit(FERR1) == 1 and not called


# --- queued writes, snapshots, statistics -------------------------------------------------------


@engines
def test_operator_writes_apply_at_the_next_scan_and_are_journaled(compiled):
    rig = Rig("TNA $02042\nYON $02000", compiled)
    rig.engine.write_bit(0o2042, 1, user="ivanov@hmi")
    rig.engine.write_word(0o4000, 0x9876)
    rig.engine.write_bytes(0o4010, b"\x01\x02")
    rig.engine.write_bit(0o40042, 1)  # HMI bit: byte 04004 bit 2
    assert rig.engine.snapshot.get_bit(0o2042) == 0  # nothing changes before the scan
    rig.step()
    snap = rig.engine.snapshot
    assert snap.get_bit(0o2000) == 1  # the program already saw the write
    assert snap.get_word(0o4000) == 0x9876 and snap.read(0o4010, 2) == b"\x01\x02"
    assert snap.get_byte(0o4004) == 0b100
    ops = [r for r in rig.sink.records if r.kind == "operator"]
    assert [r.source for r in ops] == ["ivanov@hmi", "operator", "operator", "operator"]
    assert "02042" in ops[0].text and ops[0].value == 1.0
    assert "04000" in ops[1].text and ops[1].value == 0x9876


@engines
def test_a_queued_write_to_a_gap_is_refused_and_the_scan_goes_on(compiled):
    rig = Rig("YON $02000", compiled)
    rig.engine.write_word(0o10000, 1)
    rig.step()
    assert rig.bit(0o2000) == 1
    assert any("write refused" in (r.text or "") for r in rig.sink.records)


def test_a_failing_queued_write_costs_neither_the_scan_nor_later_writes():
    rig = Rig("YON $02000")
    rig.engine.post(lambda mem: 1 / 0)
    rig.engine.write_word(0o4000, 5)
    rig.step()
    assert rig.bit(0o2000) == 1 and rig.engine.mem.get_word(0o4000) == 5
    assert any("ZeroDivisionError" in (r.text or "") for r in rig.sink.records)


@engines
def test_snapshot_is_published_after_each_scan_to_listeners(compiled):
    rig = Rig("TNA $0\nYON $02000", compiled)
    seen = []
    rig.engine.subscribe(seen.append)
    before = rig.engine.snapshot
    rig.step(b0=1)
    rig.step(b0=0)
    assert [s.scan for s in seen] == [1, 2]
    assert seen[0].get_bit(0o2000) == 1 and seen[1].get_bit(0o2000) == 0
    assert before.get_bit(0o2000) == 0  # an old snapshot never changes
    assert seen[1].time == pytest.approx(0.2) and seen[1].state == "running"


@engines
def test_post_runs_between_scans_in_order(compiled):
    rig = Rig("NOP", compiled)
    order = []
    rig.engine.post(lambda mem: order.append(1))
    rig.engine.post(lambda mem: mem.set_word(0o4000, 7))
    rig.step()
    assert order == [1] and rig.engine.mem.get_word(0o4000) == 7


def test_scan_statistics_count_time_and_overruns():
    rig = Rig("TNA $0\nYON $02000", tick=3600.0)
    rig.step(scans=5)
    st = rig.engine.stats
    assert st.count == 5 and st.overruns == 0
    assert 0 < st.last_ms <= st.max_ms and 0 < st.mean_ms <= st.max_ms
    slow = Rig("TNA $0\nYON $02000", tick=1e-9)  # every scan is longer than a 1 ns tick
    slow.step(scans=3)
    assert slow.engine.stats.overruns == 3


def test_scan_statistics_mean_is_the_running_average():
    from netplc.engine import ScanStats

    st = ScanStats()
    for ms in (1.0, 3.0, 2.0):
        st.add(ms, tick_ms=2.5)
    assert (st.count, st.last_ms, st.max_ms, st.overruns) == (3, 2.0, 3.0, 1)
    assert st.mean_ms == pytest.approx(2.0)


@engines
def test_a_listener_that_raises_is_journaled_and_the_others_go_on(compiled):
    rig = Rig("NOP", compiled)
    before, after = [], []
    calls = []

    def faulty(snap):
        calls.append(snap.scan)
        if snap.scan == 2:
            raise RuntimeError("listener bug")

    rig.engine.subscribe(before.append, "before")
    rig.engine.subscribe(faulty, "faulty")
    rig.engine.subscribe(after.append, "after")
    for _ in range(5):
        rig.step(0.1)
    assert [s.scan for s in before] == [s.scan for s in after] == calls == [1, 2, 3, 4, 5]
    assert "listener bug" in rig.engine.listener_faults["faulty"]
    faults = [r.text for r in rig.sink.records if "listener" in (r.text or "")]
    assert len(faults) == 1 and "engine listener faulty failed" in faults[0]
    unsubscribe = rig.engine.subscribe(lambda s: None, "x")
    unsubscribe()
    assert len(rig.engine.listeners) == 3


def test_a_listener_that_raises_at_every_scan_is_logged_once(caplog):
    rig = Rig("NOP")

    def faulty(snap):
        raise RuntimeError("listener bug")

    rig.engine.subscribe(faulty, "faulty")
    with caplog.at_level(logging.ERROR, logger="netplc.engine"):
        for _ in range(5):
            rig.step(0.1)
    [logged] = caplog.records
    assert "engine listener faulty failed" in logged.getMessage() and logged.exc_info is not None
    assert len([r for r in rig.sink.records if "listener" in (r.text or "")]) == 1
