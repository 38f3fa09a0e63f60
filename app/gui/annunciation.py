"""The workstation's alarm sound: the station's horn (app/scada/horn.py) made audible.

While the horn sounds, the sound file of its highest priority (`alarm_sound_p1`, `alarm_sound_p2`
in station.toml, else the shipped WAVs of app/gui/sounds/) plays in a loop through Qt
Multimedia's QSoundEffect, until the alarm is acknowledged or the sound silenced (a command of the
layer, for the roles the policy names). `QApplication.beep()` was silent on most PCs. Where Qt
Multimedia is not installed (PySide6-Essentials alone has no QtMultimedia) the console beeps once
a second instead, and says so once in the log.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from pathlib import Path

from PySide6.QtCore import QUrl
from PySide6.QtWidgets import QApplication

from app.gui.sounds import shipped
from app.scada.horn import SOUNDING, Horn

logger = logging.getLogger(__name__)

try:
    from PySide6.QtMultimedia import QSoundEffect
except ImportError:  # PySide6-Essentials without the Addons: beep instead (logged when first needed)
    QSoundEffect = None


class Annunciation:
    def __init__(self, horn: Horn | None, enabled: bool,
                 sounds: tuple[Path | None, Path | None] = (None, None),
                 beep: Callable[[], None] = QApplication.beep) -> None:
        self.horn = horn
        self.enabled = enabled
        self.files = {p: sounds[i] or shipped(p) for i, p in enumerate(SOUNDING)}
        self.beep = beep
        self.sounding = False
        self.playing: Path | None = None  # the file looping now; None: silent (or beeping)
        self._effect: object | None = None
        self._said = False

    def update(self) -> None:
        """Follow the station's horn: start, change or stop the loop."""
        priority = self.horn.priority if self.enabled and self.horn is not None else None
        self.sounding = priority is not None
        self._play(self.files.get(priority) if priority is not None else None)

    def silence(self) -> None:
        """Silenced by the layer: quiet at once (the horn says the same from the next scan)."""
        self.sounding = False
        self._play(None)

    def tick(self) -> None:
        """Once a second: follow the horn; beep where there is no sound effect."""
        self.update()
        if self.sounding and self._effect is None:
            self.beep()

    def _play(self, file: Path | None) -> None:
        if file == self.playing:
            return
        self.playing = file
        if self._effect is not None:
            self._effect.stop()  # type: ignore[attr-defined]
            self._effect = None
        if file is None:
            return
        if QSoundEffect is None:
            if not self._said:
                self._said = True
                logger.warning("Qt Multimedia is not installed (PySide6-Addons): alarms beep instead of "
                               "playing %s", file)
            return
        effect = QSoundEffect()
        effect.setSource(QUrl.fromLocalFile(str(file)))
        effect.setLoopCount(QSoundEffect.Loop.Infinite.value)
        effect.play()
        self._effect = effect

    def stop(self) -> None:
        self._play(None)
