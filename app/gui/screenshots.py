"""`python -m app.gui.screenshots DIR`: the workstation, the viewer and the designer on the demo station.

The workstation's tabs, a tag's faceplate (over the analog form), the run-time trend of LEVEL
and TEMP and the designer are taken at 1366x768 and 1920x1080, in English
(`workstation-02-analog.png`, `designer-02-analog-1920x1080.png`) and in Russian (`...-ru.png`);
`--language en` or `--language ru` takes only those (the viewer's two are taken with English).

The demo station runs for real (a copy in a temporary folder, the embedded node over TCP, its own
archive) while a short script plays the operator: Пуск pressed a few times, a setpoint entered,
the pump switched on, and the level driven over its alarm limit, so that the pictures show what an
operator sees on a working plant, not empty widgets.
"""

from __future__ import annotations

import argparse
import re
import shutil
import sys
import tempfile
import time
from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import TYPE_CHECKING

from app.station.config import DEMO_STATION, load_station

if TYPE_CHECKING:
    from PySide6.QtCore import QCoreApplication

    from app.gui.designer.window import DesignerWindow
    from app.gui.main_window import MainWindow
    from app.station.runtime import Runtime

SIZE = (1400, 900)  # the viewer's
WINDOW_SIZES = ((1366, 768), (1920, 1080))  # the smallest screen the workstation must fit; a common one
LANGUAGES = ("en", "ru")
RUN_SECONDS = 24.0
START_BIT = 0o40042
PUMP, PUMP_IND = 0o2120, 0o2121
SETPOINT = 0o4030
LEVEL = 0o4010


def copy_station(dest: Path) -> Path:
    shutil.copytree(DEMO_STATION, dest, ignore=shutil.ignore_patterns("archive", "log", "station.lock",
                                                                      "__pycache__"))
    toml = dest / "station.toml"
    toml.write_text(re.sub(r"(?m)^port = 1502$", "port = 0", toml.read_text(encoding="utf-8")),
                    encoding="utf-8")
    return dest


def slug(text: str) -> str:
    return re.sub(r"[^0-9a-z]+", "-", text.lower()).strip("-") or "form"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m app.gui.screenshots",
                                 description="Render the workstation and the viewer on the demo station.")
    ap.add_argument("out", type=Path, help="folder for the PNGs (docs/screenshots)")
    ap.add_argument("--seconds", type=float, default=RUN_SECONDS, help="how long the station runs first")
    ap.add_argument("--language", action="append", choices=LANGUAGES,
                    help="only the pictures in this language (again for more; the viewer's are in en)")
    args = ap.parse_args(argv)
    languages = [lang for lang in LANGUAGES if lang in (args.language or LANGUAGES)]

    from app.gui import i18n
    from app.gui.application import application
    from app.station.runtime import Runtime

    app = application()
    wait = partial(_pump_events, app)
    args.out.mkdir(parents=True, exist_ok=True)
    written: list[Path] = []
    with tempfile.TemporaryDirectory() as tmp:
        runtime = Runtime(load_station(copy_station(Path(tmp) / "station")))
        runtime.start()
        try:
            for n, language in enumerate(languages):
                i18n.install(app, language)  # the window's texts are translated as it is made
                suffix = "" if language == "en" else "-ru"
                written += _workstation(runtime, args.out, wait,
                                        args.seconds if n == 0 else 0.0, suffix)
                written += _designer(runtime, args.out, wait, suffix)
            i18n.install(app, "en")
        finally:
            runtime.stop()
        if "en" in languages:
            written += _viewer(runtime.station.Archive, args.out, wait)
    for path in written:
        print(path)
    return 0


def _viewer(archive: Path, out: Path, wait: Callable[[float], None]) -> list[Path]:
    """The offline viewer on the archive the run left: a page of records, and three series."""
    from app.gui.viewer import ViewerWindow

    written: list[Path] = []
    viewer = ViewerWindow(archive)
    try:
        viewer.resize(*SIZE)
        viewer.show()
        _until(wait, lambda: viewer.paging is None)  # the page is read in a thread
        path = out / "viewer-records.png"
        viewer.grab().save(str(path))
        written.append(path)
        for row in range(min(3, viewer.series_list.count())):
            viewer.check_series(row)
        viewer.tabs.setCurrentIndex(1)
        _until(wait, lambda: not viewer.loading)  # the series are read in a thread
        path = out / "viewer-series.png"
        viewer.grab().save(str(path))
        written.append(path)
    finally:
        viewer.close()
    return written


def _workstation(runtime: Runtime, out: Path, wait: Callable[[float], None], seconds: float,
                 language: str) -> list[Path]:
    """Every tab, and TEMP's faceplate over the analog form, at each window size."""
    from PySide6.QtGui import QPainter

    from app.gui.main_window import MainWindow

    window = MainWindow(runtime)
    window.resize(*WINDOW_SIZES[0])
    window.show()
    written: list[Path] = []
    try:
        if seconds > 0:  # once: the next language's window shows the same plant
            _play_operator(runtime, wait, seconds)
        window.journal.refresh()  # its newest records, without waiting for the dock's timer
        _until(wait, lambda: window.faceplates.last is not None and bool(window.journal.summary.text()))
        for size in WINDOW_SIZES:
            window.resize(*size)
            suffix = ("" if size == WINDOW_SIZES[0] else f"-{size[0]}x{size[1]}") + language
            for i, view in enumerate(window.views):
                window.tabs.setCurrentIndex(i)
                wait(0.0)  # laid out; the view shows the last scan already (every tab follows them)
                view.flush()
                path = out / f"workstation-{slug(view.form.path.stem)}{suffix}.png"
                window.grab().save(str(path))
                written.append(path)
            analog = next(i for i, v in enumerate(window.views) if v.form.path.stem == "02_analog")
            window.tabs.setCurrentIndex(analog)
            plate = window.faceplates.show_tag(next(t for t in runtime.alarms.table.tags if t.name == "TEMP"))
            _until(wait, lambda plate=plate: not plate.loading())  # its hour of history is read in a thread
            picture = window.grab()
            p = QPainter(picture)
            try:  # the dialog where a window manager would put it: over the middle of the window
                p.drawPixmap((picture.width() - plate.width()) // 2, (picture.height() - plate.height()) // 2,
                             plate.grab())
            finally:
                p.end()
            path = out / f"faceplate-temp{suffix}.png"
            picture.save(str(path))
            written.append(path)
            plate.close()
            written.append(_trend(window, out / f"trend-level-temp{suffix}.png", size, wait))
    finally:
        window.close()
    return written


def _trend(window: MainWindow, path: Path, size: tuple[int, int], wait: Callable[[float], None]) -> Path:
    """The run-time trend of LEVEL and TEMP zoomed into the last minute, the cursors on them."""
    trend = window.open_trends()
    trend.resize(*size)
    for name in ("LEVEL", "TEMP"):
        trend.add_pen(name)
    # the archive is read in a thread, the live values come with the scans
    _until(wait, lambda: not trend.loading() and all(p.live_t for p in trend.pens.values()))
    now = time.time()
    trend.set_range(now - 60, now)
    trend.set_cursors(now - 25, now - 2)
    # the minute is read again at its own detail once the zoom has settled (DETAIL_MS), then drawn
    _until(wait, lambda: not trend.settled.isActive() and not trend.loading())
    trend.redraw()
    trend.grab().save(str(path))
    trend.close()
    return path


def _designer(runtime: Runtime, out: Path, wait: Callable[[float], None], language: str) -> list[Path]:
    """The form designer on the analog form at each window size, previewing the running station
    live, a gauge selected."""
    from app.gui.designer.station import open_target
    from app.gui.designer.window import DesignerWindow
    from hmi_forms.elements.journal import MessageJournal

    window = DesignerWindow(open_target(runtime.station.path.parent / "forms" / "02_analog.hmi"))
    window.resize(*WINDOW_SIZES[0])
    window.show()
    written: list[Path] = []
    try:
        window.design.select([e for e in window.design.doc.elements if e.get("Name") == "Уровень"])
        window.start_preview("127.0.0.1", runtime.modbus.port if runtime.modbus is not None else None)
        # the memory is read over Modbus in a thread, a journal element's page in another (the
        # canvas draws the journal again when its page arrives)
        polled = _snapshots(window)
        journals = [i for i in window.design.items.values() if isinstance(i.model, MessageJournal)]
        _until(wait, lambda: polled() > 0 and all(i.widget is not None and i.widget.status.text()
                                                  for i in journals))
        for size in WINDOW_SIZES:
            window.resize(*size)
            window.canvas.home()
            wait(0.0)
            window.problems.recheck()
            suffix = ("" if size == WINDOW_SIZES[0] else f"-{size[0]}x{size[1]}") + language
            path = out / f"designer-02-analog{suffix}.png"
            window.grab().save(str(path))
            written.append(path)
        window.stop_preview()
    finally:
        window.close()
    return written


def _snapshots(window: DesignerWindow) -> Callable[[], int]:
    """How many snapshots of the preview the canvas has shown since this was called (asked often
    enough to see each: the preview polls every 0.2 s)."""
    seen = [window.design.snapshot]

    def count() -> int:
        if window.design.snapshot is not seen[-1]:
            seen.append(window.design.snapshot)
        return len(seen) - 1

    return count


def _play_operator(runtime: Runtime, wait: Callable[[float], None], seconds: float) -> None:
    """A few minutes of a shift, compressed: what makes the forms and the journal worth looking at.
    The writes name the form elements an operator would have used, as their clicks do."""
    engine = runtime.engine
    node = runtime.simulators[0].engine
    # 70 %: the temperature starts to follow
    engine.write_word(SETPOINT, 2867, user="operator", label="Уставка температуры")
    engine.write_bit(PUMP_IND, 1, user="operator", label="Индикация насоса")
    wait(1.0)
    engine.write_bit(PUMP, 1, user="operator", label="Насос")
    node.write_word(LEVEL, 3300)  # the tank is nearly full: the level alarm comes during the run
    start = time.monotonic()
    pressed = 0
    while time.monotonic() - start < seconds:
        engine.write_bit(START_BIT, 1 - pressed % 2, user="operator", label="Пуск")
        pressed += 1
        wait(1.2)


def _until(wait: Callable[[float], None], done: Callable[[], bool], seconds: float = 30.0) -> None:
    """Events handled until `done()` (a read in a thread answered), for at most `seconds`: no
    picture waits longer than what it shows needs."""
    deadline = time.monotonic() + seconds
    while not done() and time.monotonic() < deadline:
        wait(0.02)


def _pump_events(app: QCoreApplication, seconds: float) -> None:
    """The events of `seconds` handled; of none: those posted so far (a resize's layout)."""
    end = time.monotonic() + seconds
    app.processEvents()
    while time.monotonic() < end:
        time.sleep(0.01)
        app.processEvents()


if __name__ == "__main__":
    sys.exit(main())
