"""The console's Russian is complete: every string the console passes through tr() (or translate)
has a finished translation in app/gui/i18n/console_ru.ts. Qt's own lupdate reads the sources into
a copy of the catalogue; a string it finds new, or an entry left unfinished or empty, fails."""

from __future__ import annotations

import shutil
import subprocess
import xml.etree.ElementTree as ET
from pathlib import Path

from app.gui.i18n import HERE, LRELEASE
from tests.app.conftest import REPO

LUPDATE = LRELEASE.with_name("lupdate")
SOURCES = ("app/gui", "hmi_forms/widgets")  # where the console's strings are


def untranslated(ts: Path) -> list[str]:
    missing = []
    for context in ET.parse(ts).getroot().iter("context"):
        name = context.findtext("name")
        for message in context.iter("message"):
            translation = message.find("translation")
            kind = translation.get("type") if translation is not None else "unfinished"
            if kind in ("vanished", "obsolete"):
                continue  # looked up by a computed text (the trend's "%1 min"): kept as it is
            if kind == "unfinished" or translation is None or not (translation.text or "").strip():
                missing.append(f"{name}: {message.findtext('source')}")
    return missing


def test_every_console_string_has_a_russian_translation(tmp_path: Path) -> None:
    ts = tmp_path / "console_ru.ts"
    shutil.copy(HERE / "console_ru.ts", ts)
    subprocess.run([str(LUPDATE), "-silent", "-locations", "none", "-extensions", "py", *SOURCES,
                    "-ts", str(ts)],
                   cwd=REPO, check=True, timeout=60)
    assert untranslated(ts) == []


def test_an_unfinished_entry_fails(tmp_path: Path) -> None:
    ts = tmp_path / "console_ru.ts"
    ts.write_text('<?xml version="1.0" encoding="utf-8"?>\n<TS version="2.1" language="ru_RU"><context>'
                  "<name>MainWindow</name><message><source>Quit</source><translation type=\"unfinished\"/>"
                  "</message><message><source>Run</source><translation>Пуск</translation></message>"
                  "</context></TS>", encoding="utf-8")
    assert untranslated(ts) == ["MainWindow: Quit"]
