"""The horn of the running demo station: its bit (`alarm_horn`) follows the alarms, and a silence
by a role the policy allows stops it, journaled; the console plays the priority's sound file."""

from __future__ import annotations

from pathlib import Path

from app.authority import Source, Who
from app.gui.alarm_summary import AlarmSummary
from app.gui.sounds import shipped
from app.station.config import load_station
from app.station.runtime import Runtime

LEVEL, HORN = 0o4010, 0o3600


def test_the_horn_bit_sounds_with_a_high_alarm_until_silenced(qtbot, demo_copy: Path) -> None:
    station = load_station(demo_copy)
    assert station.alarm_horn == HORN
    runtime = Runtime(station)
    runtime.start()
    try:
        engine = runtime.engine
        summary = AlarmSummary(runtime.alarms, runtime.commands, lambda: Who("operator", Source.CONSOLE))
        qtbot.addWidget(summary)
        qtbot.waitUntil(lambda: runtime.status().nodes_up == 1, timeout=10_000)
        assert engine.snapshot.get_hmi_bit(HORN) == 0
        runtime.simulators[0].engine.write_word(LEVEL, 3950)  # 96 %: LEVEL.HH (priority 2)
        qtbot.waitUntil(lambda: engine.snapshot.get_hmi_bit(HORN) == 1, timeout=10_000)
        summary.annunciator.tick()
        assert summary.annunciator.sounding and summary.annunciator.playing == shipped(2)
        viewer = Who("viewer", Source.CONSOLE)
        assert not runtime.commands.silence(viewer).result(5).ok  # the policy's role, not the view's
        assert engine.snapshot.get_hmi_bit(HORN) == 1
        summary.silence_sound()
        qtbot.waitUntil(lambda: engine.snapshot.get_hmi_bit(HORN) == 0, timeout=10_000)
        qtbot.waitUntil(lambda: not summary.annunciator.sounding and summary.annunciator.playing is None,
                        timeout=5000)
        summary.stop()
    finally:
        runtime.stop()
