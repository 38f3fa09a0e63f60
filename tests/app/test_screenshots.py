"""`python -m app.gui.screenshots`: the manual's pictures come from the running demo station.

One test per language (this file and test_screenshots_ru.py), each with its own station, so
that xdist runs them side by side; `make screenshots` takes both in one run."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtGui import QImage

from app.gui.screenshots import main
from app.station.config import DEMO_STATION


def pictures(language: str) -> list[str]:
    """Every picture of the workstation and the designer in `language` ("" or "-ru")."""
    forms = sorted(p.stem for p in (DEMO_STATION / "forms").glob("*.hmi"))
    shots = [f"workstation-{f.replace('_', '-')}" for f in forms] + ["faceplate-temp", "trend-level-temp",
                                                                      "designer-02-analog"]
    return [f"{s}{size}{language}.png" for s in shots for size in ("", "-1920x1080")]


def check_pictures(folder: Path, language: str, others: list[str]) -> None:
    """All of them and nothing else, at both window sizes, the last one a rendered window."""
    names = sorted(p.name for p in folder.glob("*.png"))
    assert names == sorted([*pictures(language), *others])
    for shot in ("workstation-01-trigger", "designer-02-analog"):
        small = QImage(str(folder / f"{shot}{language}.png"))
        large = QImage(str(folder / f"{shot}-1920x1080{language}.png"))
        assert (small.width(), small.height()) == (1366, 768)
        assert (large.width(), large.height()) == (1920, 1080)
    image = QImage(str(folder / names[-1]))
    assert image.width() > 1000 and image.height() > 700
    colours = {image.pixel(x, y) for x in range(0, image.width(), 37) for y in range(0, image.height(), 41)}
    assert len(colours) > 20  # a rendered window, not a blank one


def test_screenshots_of_every_form_and_the_viewer_in_english(qtbot, tmp_path: Path) -> None:
    assert main([str(tmp_path), "--seconds", "0.5", "--language", "en"]) == 0
    check_pictures(tmp_path, "", ["viewer-records.png", "viewer-series.png"])
