"""Form designer: open a 1,000-element form, move 500 elements at once, save it.

The form: 300 dials, 300 discrete colour labels, 200 digital readouts, 100 captions and 100 bit
graphs on a 64 px grid. Each figure includes the repaint Qt does for it (processEvents) under the
offscreen platform: open = read the file, build the window (1366x768) and paint it; move = one
undoable step moving 500 selected elements by a grid step; save = the problems check `check`
would run, then the canonical write. The yardstick, measured in the same run: creating and
showing 1,000 plain QLabels in one window.

    QT_QPA_PLATFORM=offscreen python bench/designer.py [runs]
"""

from __future__ import annotations

import json
import os
import statistics
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")

from PySide6.QtWidgets import QApplication, QLabel, QWidget

from app.gui.designer.station import Context
from app.gui.designer.window import DesignerWindow
from hmi_forms.form_doc import problems, read_doc

COLS, TILE = 40, 64
TARGET_MS = 200.0


def generate(path: Path) -> Path:
    elements = []
    for i in range(1000):
        x, y = i % COLS * TILE, i // COLS * TILE
        geo = {"x": x, "y": y, "w": TILE, "h": TILE}
        if i < 300:
            el = {"type": "AnalogBase", "Name": f"D{i}", **geo, "InAddr": f"0{0o4000 + 2 * i:o}",
                  "Device": "Raw", "Units": "%", "Appearance": "dial", "PhyHigh": 90}
        elif i < 600:
            el = {"type": "DiscreteColorLabel", "Name": f"L{i}", **geo, "InAddr": f"0{0o2000 + i % 512:o}",
                  "TextFalse": "OFF", "TextTrue": "ON", "BackColorTrue": "#2e7d32"}
        elif i < 800:
            el = {"type": "AnalogBase", "Name": f"N{i}", **geo, "InAddr": f"0{0o5000 + 2 * (i - 600):o}",
                  "Device": "Raw", "Units": "%", "Appearance": "digital"}
        elif i < 900:
            el = {"type": "StaticText", "Name": f"T{i}", **geo, "Text": f"Caption {i}"}
        else:
            el = {"type": "Graph", "Name": f"G{i}", **geo, "Address": f"0{0o2000 + i % 512:o}",
                  "Elements": 50}
        elements.append(el)
    doc = {"form": {"title": "bench", "width": COLS * TILE, "height": 1000 // COLS * TILE},
           "devices": [{"Name": "Raw", "AppMin": 0, "AppMax": 65535, "PhyMin": 0, "PhyMax": 100}],
           "elements": elements}
    path.write_text(json.dumps(doc, ensure_ascii=False), encoding="utf-8")
    return path


def timed(fn: Callable[[], object]) -> float:
    t = time.perf_counter()
    fn()
    QApplication.processEvents()
    return (time.perf_counter() - t) * 1000


def yardstick(app: QApplication) -> float:
    def build() -> QWidget:
        top = QWidget()
        top.resize(1366, 768)
        for i in range(1000):
            label = QLabel(f"label {i}", top)
            label.setGeometry(i % COLS * TILE, i // COLS * TILE, TILE, TILE)
        top.show()
        return top

    holder: list[QWidget] = []
    ms = timed(lambda: holder.append(build()))
    holder[0].close()
    holder[0].deleteLater()
    app.processEvents()
    return ms


def one_run(app: QApplication, path: Path) -> tuple[float, float, float, float]:
    windows: list[DesignerWindow] = []

    def open_form() -> None:
        w = DesignerWindow(Context(None, path))
        w.confirm = lambda question: True  # type: ignore[method-assign]
        w.show()
        windows.append(w)

    t_open = timed(open_form)
    w = windows[0]
    d = w.design
    half = d.doc.elements[::2]
    d.select(half)
    app.processEvents()
    t_move = timed(lambda: d.move_by(half, TILE // 8, 0))
    assert d.doc.elements[0]["x"] == TILE // 8 and d.undo.count() == 1
    t_save = timed(lambda: w.save(path.with_name("saved.hmi")))
    assert not problems(read_doc(path.with_name("saved.hmi")), {})
    base = yardstick(app)
    d.undo.setClean()
    w.close()
    w.deleteLater()
    app.processEvents()
    return t_open, t_move, t_save, base


def main() -> int:
    runs = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    app = QApplication.instance() or QApplication(sys.argv[:1])
    with tempfile.TemporaryDirectory() as tmp:
        path = generate(Path(tmp) / "bench.hmi")
        one_run(app, path)  # warm-up: imports, fonts, first pyqtgraph plot
        results = [one_run(app, path) for _ in range(runs)]
    names = ("open 1,000 elements", "move 500 elements", "save 1,000 elements")
    base = statistics.median(r[3] for r in results)
    print(f"yardstick: 1,000 plain QLabels created and shown: {base:.1f} ms (median of {runs})")
    for i, name in enumerate(names):
        values = [r[i] for r in results]
        med = statistics.median(values)
        verdict = "met" if max(values) <= TARGET_MS else "missed in some run"
        print(f"{name}: {min(values):.1f}-{max(values):.1f} ms, median {med:.1f} ms "
              f"({med / base:.2f}x the yardstick); target <= {TARGET_MS:.0f} ms: {verdict}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
