"""The manual's Russian pictures (test_screenshots.py takes the English ones beside it): the
station's Russian translation installed before each window is made."""

from __future__ import annotations

from pathlib import Path

from app.gui.screenshots import main
from tests.app.test_screenshots import check_pictures


def test_screenshots_of_every_form_in_russian(qtbot, tmp_path: Path) -> None:
    assert main([str(tmp_path), "--seconds", "0", "--language", "ru"]) == 0
    check_pictures(tmp_path, "-ru", [])
