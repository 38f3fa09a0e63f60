"""`python -m app.gui.screenshots`: the manual's pictures come from the running demo station."""

from __future__ import annotations

from pathlib import Path

from PySide6.QtGui import QImage

from app.gui.screenshots import main
from app.station.config import DEMO_STATION


def test_screenshots_of_every_form_and_the_viewer(qtbot, tmp_path: Path) -> None:
    assert main([str(tmp_path), "--seconds", "1.5"]) == 0
    names = sorted(p.name for p in tmp_path.glob("*.png"))
    forms = sorted(p.stem for p in (DEMO_STATION / "forms").glob("*.hmi"))
    shots = [f"workstation-{f.replace('_', '-')}" for f in forms] + ["faceplate-temp", "trend-level-temp",
                                                                      "designer-02-analog"]
    assert names == sorted([*(f"{s}{size}{language}.png" for s in shots for size in ("", "-1920x1080")
                              for language in ("", "-ru")), "viewer-records.png", "viewer-series.png"])
    for shot in ("workstation-01-trigger", "designer-02-analog"):
        for language in ("", "-ru"):
            small = QImage(str(tmp_path / f"{shot}{language}.png"))
            large = QImage(str(tmp_path / f"{shot}-1920x1080{language}.png"))
            assert (small.width(), small.height()) == (1366, 768)
            assert (large.width(), large.height()) == (1920, 1080)
    image = QImage(str(tmp_path / names[-1]))
    assert image.width() > 1000 and image.height() > 700
    colours = {image.pixel(x, y) for x in range(0, image.width(), 37) for y in range(0, image.height(), 41)}
    assert len(colours) > 20  # a rendered window, not a blank one
