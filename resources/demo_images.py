"""Draws the demo forms' pictures (pump frames, tank) into app/station/demo/forms/images/:
`python resources/demo_images.py`.

Kept as code so the pictures can be regenerated at another size or style; the PNGs are committed.
"""

from __future__ import annotations

import math
import os
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtCore import QPointF, QRectF, Qt
from PySide6.QtGui import QColor, QGuiApplication, QImage, QPainter, QPen, QPolygonF

HERE = Path(__file__).resolve().parents[1] / "app" / "station" / "demo" / "forms" / "images"
SIZE = 96


def pump(path: Path, running: bool, angle: float) -> None:
    img = QImage(SIZE, SIZE, QImage.Format.Format_ARGB32)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    body = QColor("#2e7d32") if running else QColor("#9aa1ab")
    c = QPointF(SIZE / 2, SIZE / 2)
    p.setPen(QPen(QColor("#33393f"), 3))
    p.setBrush(QColor("#e3e6ea"))
    p.drawRect(QRectF(c.x() - 6, 4, SIZE / 2 + 2, 16))  # outlet
    p.setBrush(body)
    p.drawEllipse(c, SIZE * 0.4, SIZE * 0.4)
    p.setBrush(QColor("#ffffff"))
    p.setPen(QPen(QColor("#33393f"), 2))
    for k in range(3):
        a = math.radians(angle + k * 120)
        tip = QPointF(c.x() + SIZE * 0.3 * math.cos(a), c.y() - SIZE * 0.3 * math.sin(a))
        s1 = QPointF(c.x() + 6 * math.cos(a + 1.2), c.y() - 6 * math.sin(a + 1.2))
        s2 = QPointF(c.x() + 6 * math.cos(a - 1.2), c.y() - 6 * math.sin(a - 1.2))
        p.drawPolygon(QPolygonF([tip, s1, s2]))
    p.setBrush(QColor("#33393f"))
    p.drawEllipse(c, 5, 5)
    p.end()
    img.save(str(path))


def tank(path: Path) -> None:
    """The vessel only: a painted fill would show one level forever (the level is on the gauges)."""
    w, h = 120, 160
    img = QImage(w, h, QImage.Format.Format_ARGB32)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setRenderHint(QPainter.RenderHint.Antialiasing)
    p.setPen(QPen(QColor("#33393f"), 3))
    p.setBrush(QColor("#e3e6ea"))
    p.drawRoundedRect(QRectF(10, 14, w - 20, h - 28), 14, 14)
    p.drawLine(QPointF(w / 2, 0), QPointF(w / 2, 14))
    p.end()
    img.save(str(path))


def pipe(path: Path) -> None:
    """The pipe from the tank to the pump: a static part of the mimic, drawn under both."""
    w, h = 60, 16
    img = QImage(w, h, QImage.Format.Format_ARGB32)
    img.fill(Qt.GlobalColor.transparent)
    p = QPainter(img)
    p.setPen(QPen(QColor("#33393f"), 2))
    p.setBrush(QColor("#9aa1ab"))
    p.drawRect(QRectF(1, 3, w - 2, h - 6))
    p.end()
    img.save(str(path))


def main() -> None:
    QGuiApplication([])
    pump(HERE / "pump_off.png", False, 90)
    for i in range(4):
        pump(HERE / f"pump_on_{i}.png", True, 90 - i * 30)
    tank(HERE / "tank.png")
    pipe(HERE / "pipe.png")


if __name__ == "__main__":
    main()
