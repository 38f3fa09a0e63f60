"""The shipped alarm sounds, one WAV per sounding priority, and how they were made.

`p1.wav` (critical) is a fast two-tone warble, `p2.wav` (high) a slower single beep: each is one
period of a loop the workstation repeats until the alarm is acknowledged or silenced, so the two
are told apart by ear before the screen is seen. `alarm_sound_p1` / `alarm_sound_p2` in
station.toml replace them. `python -m app.gui.sounds` writes them again (mono, 16-bit, 22.05 kHz).
"""

from __future__ import annotations

import math
import struct
import wave
from pathlib import Path

HERE = Path(__file__).resolve().parent
RATE = 22_050
# priority: (tone Hz, seconds) pieces of one period; 0 Hz is silence
PATTERNS: dict[int, tuple[tuple[float, float], ...]] = {
    1: ((960.0, 0.12), (770.0, 0.12), (960.0, 0.12), (770.0, 0.12), (0.0, 0.12)),
    2: ((880.0, 0.25), (0.0, 0.55)),
}


def shipped(priority: int) -> Path:
    return HERE / f"p{priority}.wav"


def write(path: Path, pieces: tuple[tuple[float, float], ...], volume: float = 0.5) -> None:
    frames = bytearray()
    for hz, seconds in pieces:
        n = int(RATE * seconds)
        fade = min(n // 2, int(RATE * 0.005))  # 5 ms ramps: no clicks between the pieces
        for i in range(n):
            ramp = min(1.0, i / fade, (n - 1 - i) / fade) if fade else 1.0
            sample = volume * ramp * math.sin(2 * math.pi * hz * i / RATE) if hz else 0.0
            frames += struct.pack("<h", int(sample * 32767))
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(RATE)
        w.writeframes(bytes(frames))


def main() -> None:
    for priority, pieces in PATTERNS.items():
        write(shipped(priority), pieces)
        print(shipped(priority))
