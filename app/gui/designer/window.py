"""The form designer's window (`python main.py design [FORM.hmi | STATION]`), the manual's ФрегатБаза.

The canvas in the middle, the element palette on the left, the property editor on the right and
the problems pane below; Edit -> Add element adds any of the 13 element types, as in the manual
("Правка -> Добавить элемент -> ..."). Everything that changes the form is one undo step.
"""

from __future__ import annotations

import sys
from pathlib import Path

from PySide6.QtCore import QT_TRANSLATE_NOOP, QPointF, QSize, Qt
from PySide6.QtGui import QAction, QCloseEvent, QGuiApplication, QKeySequence, QShowEvent
from PySide6.QtWidgets import (
    QDockWidget,
    QFileDialog,
    QInputDialog,
    QLabel,
    QMainWindow,
    QMessageBox,
    QWidget,
)

from app.gui import i18n
from app.gui.designer.canvas import Canvas
from app.gui.designer.design import Design
from app.gui.designer.palette import Palette
from app.gui.designer.preview import Preview, plan
from app.gui.designer.problems import ProblemsPane
from app.gui.designer.properties import PropertyPanel
from app.gui.designer.station import Context, open_target
from app.gui.designer.tag_browser import TagBrowser
from app.scada.words import words
from hmi_forms.elements import ELEMENT_TYPES
from hmi_forms.form import FormError
from hmi_forms.form_doc import FormDoc, new_doc, read_doc

SIZE = QSize(1366, 768)
SAVE_ANYWAY = QT_TRANSLATE_NOOP(
    "DesignerWindow", "{0} problem(s), see Problems: the station will not open the form. Save anyway?")
RTU_PREVIEW = QT_TRANSLATE_NOOP(
    "DesignerWindow", "The station serves Modbus RTU on a serial port; the preview reads Modbus TCP")
ALIGN = ((QT_TRANSLATE_NOOP("DesignerWindow", "Align left"), "left"),
         (QT_TRANSLATE_NOOP("DesignerWindow", "Align right"), "right"),
         (QT_TRANSLATE_NOOP("DesignerWindow", "Align top"), "top"),
         (QT_TRANSLATE_NOOP("DesignerWindow", "Align bottom"), "bottom"),
         (QT_TRANSLATE_NOOP("DesignerWindow", "Centre horizontally"), "hcenter"),
         (QT_TRANSLATE_NOOP("DesignerWindow", "Centre vertically"), "vcenter"))
Z_ORDER = ((QT_TRANSLATE_NOOP("DesignerWindow", "Bring to front"), "front", "Ctrl+Shift+]"),
           (QT_TRANSLATE_NOOP("DesignerWindow", "Raise"), "raise", "Ctrl+]"),
           (QT_TRANSLATE_NOOP("DesignerWindow", "Lower"), "lower", "Ctrl+["),
           (QT_TRANSLATE_NOOP("DesignerWindow", "Send to back"), "back", "Ctrl+Shift+["))


class DesignerWindow(QMainWindow):
    def __init__(self, context: Context, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.context = context
        self.preview: Preview | None = None
        self.design = self._design(self._read(context.form))
        self.canvas = Canvas(self.design)
        self.setCentralWidget(self.canvas)
        names = sorted(context.names)
        self.palette = Palette(self.add)
        self.tag_browser = TagBrowser(context.tags, self.add_tag)
        self.properties = PropertyPanel(self.design, names)
        self.problems_label = QLabel()
        self.preview_label = QLabel()
        self.problems = ProblemsPane(self.design, self._problem_count)
        self._dock("Elements", self.tr("Elements"), self.palette, Qt.DockWidgetArea.LeftDockWidgetArea)
        self._dock("Tags", self.tr("Tags"), self.tag_browser, Qt.DockWidgetArea.LeftDockWidgetArea)
        self._dock("Properties", self.tr("Properties"), self.properties,
                   Qt.DockWidgetArea.RightDockWidgetArea)
        self.problems_dock = self._dock("Problems", self.tr("Problems"), self.problems,
                                        Qt.DockWidgetArea.BottomDockWidgetArea)
        self.statusBar().addWidget(self.problems_label)
        self.statusBar().addPermanentWidget(self.preview_label)
        self._build_menus()
        self._connect()
        self.problems.schedule()  # a moment after the window shows: opening a big form stays quick
        self.properties.show_selection()
        self.resize(SIZE)
        self._sized = False

    # --- documents ------------------------------------------------------------------------------

    def _read(self, path: Path) -> FormDoc:
        if not path.exists():
            return new_doc(path)
        return read_doc(path)

    def _design(self, doc: FormDoc) -> Design:
        station = self.context.station
        if station is not None:
            doc.station, doc.allow_outside = station.folder, station.allow_outside
        doc.language = self.context.language
        doc.tags = self.context.tags
        archive = station.Archive if station is not None and station.Archive.is_file() else None
        return Design(doc, self.context.names, archive, self)

    def _connect(self) -> None:
        d = self.design
        d.changed.connect(self._changed)
        d.selection_changed.connect(self.properties.show_selection)
        d.clean_changed.connect(self._title)
        self._title()

    def set_document(self, doc: FormDoc) -> None:
        old = self.design
        self.design = self._design(doc)
        self.canvas.set_design(self.design)
        self.canvas.home()
        self.properties.set_design(self.design)
        self.problems.set_design(self.design)
        self._rebind_undo()
        self._connect()
        old.deleteLater()
        self._update_plan()

    def _changed(self) -> None:
        self.problems.schedule()
        self.properties.show_selection()
        self._title()
        self._update_plan()

    def _title(self, *_: object) -> None:
        star = "" if self.design.undo.isClean() else "*"
        name = f"{self.design.doc.path.name}{star}"
        self.setWindowTitle(self.tr("{0} - NetPlc form designer").format(name))

    def _problem_count(self, n: int, warned: int = 0) -> None:
        text = self.tr("{0} problem(s): see Problems").format(n) if n else self.tr("No problems")
        if warned:
            text += self.tr(", {0} warning(s)").format(warned)
        self.problems_label.setText(text)

    def _dock(self, name: str, title: str, widget: QWidget, area: Qt.DockWidgetArea) -> QDockWidget:
        dock = QDockWidget(title, self)
        dock.setObjectName(name)
        dock.setWidget(widget)
        dock.setFeatures(QDockWidget.DockWidgetFeature.DockWidgetMovable
                         | QDockWidget.DockWidgetFeature.DockWidgetFloatable)
        self.addDockWidget(area, dock)
        return dock

    # --- menus ----------------------------------------------------------------------------------

    def _action(self, menu: object, text: str, slot: object,
                shortcut: str | QKeySequence.StandardKey | None = None, checkable: bool = False) -> QAction:
        action = QAction(text, self)
        if shortcut is not None:
            action.setShortcut(QKeySequence(shortcut))
        action.setCheckable(checkable)
        action.triggered.connect(slot)
        menu.addAction(action)  # type: ignore[attr-defined]
        return action

    def _build_menus(self) -> None:
        bar = self.menuBar()
        keys = QKeySequence.StandardKey
        file = bar.addMenu(self.tr("&File"))
        self._action(file, self.tr("&New form…"), self.new_form, keys.New)
        self._action(file, self.tr("&Open…"), self.open_form, keys.Open)
        if self.context.forms:
            station = file.addMenu(self.tr("Forms of the station"))
            for path in self.context.forms:
                self._action(station, path.name,
                             lambda _=False, p=path: self._may_discard() and self.open_path(p))
        self._action(file, self.tr("&Save"), lambda: self.save(), keys.Save)
        self._action(file, self.tr("Save &as…"), self.save_as, keys.SaveAs)
        file.addSeparator()
        self._action(file, self.tr("&Close"), self.close, keys.Quit)

        edit = bar.addMenu(self.tr("&Edit"))
        self.edit_menu = edit
        self.undo_action = self._action(edit, self.tr("&Undo"), lambda: self.design.undo.undo(), keys.Undo)
        self.redo_action = self._action(edit, self.tr("&Redo"), lambda: self.design.undo.redo(), keys.Redo)
        edit.addSeparator()
        self._action(edit, self.tr("Cu&t"), self.cut, keys.Cut)
        self._action(edit, self.tr("&Copy"), self.copy, keys.Copy)
        self._action(edit, self.tr("&Paste"), self.paste, keys.Paste)
        self._action(edit, self.tr("&Delete"), lambda: self.design.delete(self.design.selected()),
                     keys.Delete)
        self._action(edit, self.tr("Select &all"), self.select_all, keys.SelectAll)
        edit.addSeparator()
        add = edit.addMenu(self.tr("Add &element"))
        self.add_actions = {kind: self._action(add, kind, lambda _=False, k=kind: self.add(k))
                            for kind in ELEMENT_TYPES}

        arrange = bar.addMenu(self.tr("&Arrange"))
        for text, how in ALIGN:
            self._action(arrange, self.tr(text), lambda _=False, h=how: self.design.align(h))
        arrange.addSeparator()
        self._action(arrange, self.tr("Distribute horizontally"), lambda: self.design.distribute("h"))
        self._action(arrange, self.tr("Distribute vertically"), lambda: self.design.distribute("v"))
        arrange.addSeparator()
        for text, how, key in Z_ORDER:
            self._action(arrange, self.tr(text), lambda _=False, h=how: self.design.z_order(h), key)
        arrange.addSeparator()
        self.snap_action = self._action(arrange, self.tr("Snap to &grid"), self._toggle_snap, "Ctrl+G",
                                        checkable=True)
        self.snap_action.setChecked(True)
        self.grid_action = self._action(arrange, self.tr("Show grid"), self._toggle_grid, checkable=True)
        self.grid_action.setChecked(True)
        self._action(arrange, self.tr("Grid size…"), self._grid_size)

        view = bar.addMenu(self.tr("&View"))
        self.preview_action = self._action(view, self.tr("&Preview live"), self.toggle_preview, "F6",
                                           checkable=True)
        station = self.context.station
        if station is None or not station.modbus_server.enabled:
            self.preview_action.setEnabled(False)
            self.preview_action.setToolTip(self.tr("No station with a Modbus server beside this form"))
        elif station.modbus_server.serial is not None:
            self.preview_action.setEnabled(False)
            self.preview_action.setToolTip(self.tr(RTU_PREVIEW))
        view.addSeparator()
        self._action(view, self.tr("Zoom in"), lambda: self.canvas.scale(1.25, 1.25), keys.ZoomIn)
        self._action(view, self.tr("Zoom out"), lambda: self.canvas.scale(0.8, 0.8), keys.ZoomOut)
        self._action(view, self.tr("Actual size"), self.canvas.resetTransform, "Ctrl+0")
        tools = self.addToolBar(self.tr("Designer"))
        tools.setObjectName("designer-tools")
        tools.addAction(self.undo_action)
        tools.addAction(self.redo_action)
        tools.addSeparator()
        tools.addAction(self.snap_action)
        tools.addAction(self.preview_action)
        self._rebind_undo()

    def add(self, kind: str) -> None:
        """Edit -> Add element."""
        self.design.add(kind, self._next_place())

    def add_tag(self, name: str) -> None:
        """A double-clicked tag of the tag browser: its element."""
        self.design.add_tag(name, self._next_place())

    def _next_place(self) -> QPointF:
        """Near the top left of what the canvas shows, each next one a little further down, so a
        series of adds does not pile up."""
        seen = self.canvas.mapToScene(self.canvas.viewport().rect()).boundingRect()
        n = len(self.design.doc.elements) % 10
        step = 2 * self.design.grid * (n + 1)
        return QPointF(max(seen.left(), 0) + step, max(seen.top(), 0) + step)

    def _rebind_undo(self) -> None:
        """Undo and Redo follow this form's stack and name the step they would take."""
        undo = self.design.undo
        self.undo_action.setEnabled(undo.canUndo())
        self.redo_action.setEnabled(undo.canRedo())
        undo.canUndoChanged.connect(self.undo_action.setEnabled)
        undo.canRedoChanged.connect(self.redo_action.setEnabled)
        undo.undoTextChanged.connect(self._undo_text)
        undo.redoTextChanged.connect(self._redo_text)

    def _undo_text(self, text: str) -> None:
        self.undo_action.setText(self.tr("&Undo {0}").format(text).strip())

    def _redo_text(self, text: str) -> None:
        self.redo_action.setText(self.tr("&Redo {0}").format(text).strip())

    def _toggle_snap(self, on: bool) -> None:
        self.design.snapping = on

    def _toggle_grid(self, on: bool) -> None:
        self.design.grid_visible = on
        self.design.scene.update()

    def _grid_size(self) -> None:
        n, ok = QInputDialog.getInt(self, self.tr("Grid"), self.tr("Grid step, pixels:"), self.design.grid,
                                    2, 100)
        if ok:
            self.design.grid = n
            self.design.scene.update()

    # --- clipboard ------------------------------------------------------------------------------

    def copy(self) -> None:
        """The selected elements as JSON text, the way a form file writes them (so they also paste
        into a text editor, and elements copied from a form file paste here). Plain text rather than
        a QMimeData of ours: the clipboard would delete that after Python has gone, at exit."""
        raws = self.design.selected()
        if raws:
            QGuiApplication.clipboard().setText(self.design.copy_text(raws))

    def cut(self) -> None:
        self.copy()
        self.design.delete(self.design.selected())

    def paste(self) -> None:
        self.design.paste_text(QGuiApplication.clipboard().text())

    def select_all(self) -> None:
        self.design.select(list(self.design.doc.elements))

    # --- files ----------------------------------------------------------------------------------

    def confirm(self, question: str) -> bool:
        """Ask the engineer (a test answers by replacing this method)."""
        answer = QMessageBox.question(self, self.tr("Form designer"), question)
        return answer == QMessageBox.StandardButton.Yes

    def warn(self, text: str) -> None:
        """Tell the engineer what went wrong (also on stderr, for a designer started from a shell)."""
        print(text, file=sys.stderr)
        QMessageBox.warning(self, self.tr("Form designer"), text)

    def save(self, path: Path | None = None) -> bool:
        """Save; the problems are worked out first and, when there are any, shown and confirmed."""
        found = self.problems.recheck()
        if found:
            self.problems_dock.show()
            self.problems_dock.raise_()
            if not self.confirm(self.tr(SAVE_ANYWAY).format(len(found))):
                return False
        try:
            saved = self.design.save(path)
        except OSError as e:
            self.warn(self.tr("The form was not saved: {0}").format(e))
            return False
        self._title()
        self.statusBar().showMessage(self.tr("Saved {0}").format(saved), 5000)
        return True

    def save_as(self) -> None:
        name, _ = QFileDialog.getSaveFileName(self, self.tr("Save form as"), str(self.design.doc.path),
                                              self.tr("Forms (*.hmi)"))
        if name:
            self.save(Path(name))

    def _folder(self) -> str:
        return str(self.design.doc.path.parent)

    def _may_discard(self) -> bool:
        return self.design.undo.isClean() or self.confirm(
            self.tr("Discard the unsaved changes of this form?"))

    def open_form(self) -> None:
        name, _ = QFileDialog.getOpenFileName(self, self.tr("Open form"), self._folder(),
                                              self.tr("Forms (*.hmi)"))
        if name and self._may_discard():
            self.open_path(Path(name))

    def open_path(self, path: Path) -> bool:
        try:
            doc = read_doc(path)
        except FormError as e:
            self.warn("\n".join(e.said(words(self.context.language))))
            return False
        self.set_document(doc)
        return True

    def new_form(self) -> None:
        name, _ = QFileDialog.getSaveFileName(self, self.tr("New form"), self._folder(),
                                              self.tr("Forms (*.hmi)"))
        if name and self._may_discard():
            self.set_document(new_doc(Path(name)))

    def showEvent(self, event: QShowEvent) -> None:
        """Give the canvas the room (dock sizes only apply once the window is laid out)."""
        super().showEvent(event)
        if not self._sized:
            self._sized = True
            self.resizeDocks([self.palette.parentWidget(), self.properties.parentWidget()],  # type: ignore[list-item]
                             [190, 330], Qt.Orientation.Horizontal)
            self.resizeDocks([self.problems_dock], [110], Qt.Orientation.Vertical)

    def closeEvent(self, event: QCloseEvent) -> None:
        if not self._may_discard():
            event.ignore()
            return
        self.stop_preview()
        event.accept()

    # --- preview --------------------------------------------------------------------------------

    def toggle_preview(self, on: bool) -> None:
        if on:
            self.start_preview()
        else:
            self.stop_preview()

    def start_preview(self, host: str | None = None, port: int | None = None) -> None:
        station = self.context.station
        server = station.modbus_server if station is not None else None
        host = host or (server.host if server is not None else "127.0.0.1")
        port = port if port is not None else (server.port if server is not None else 1502)
        self.stop_preview()
        self.preview = Preview(host, port, (server.unit if server is not None else None) or 1)
        self.preview.snapshot.connect(self.design.show_snapshot)
        self.preview.status.connect(self.preview_label.setText)
        self._update_plan()
        self.preview.start()
        self.preview_action.setChecked(True)

    def stop_preview(self) -> None:
        if self.preview is not None:
            self.preview.stop()
            self.preview = None
            self.preview_label.setText("")
        self.preview_action.setChecked(False)

    def _update_plan(self) -> None:
        if self.preview is not None:
            self.preview.snapshot.disconnect()
            self.preview.snapshot.connect(self.design.show_snapshot)
            self.preview.requests = plan(i.model for i in self.design.items.values()
                                         if i.model is not None and not i.problems)


def run_designer(target: str, screenshot: str | None = None) -> int:
    """`python main.py design [FORM.hmi | STATION]`; with `screenshot`, render the window to a PNG
    at 1366x768 and exit (for the documentation and for checking a form without a display)."""
    try:
        context = open_target(target)
    except ValueError as e:
        print(e, file=sys.stderr)
        return 2
    from app.gui.application import application

    app = application()
    i18n.install(app, context.language)
    try:
        window = DesignerWindow(context)
    except FormError as e:
        print("\n".join(e.said(words(context.language))), file=sys.stderr)
        return 2
    window.show()
    window.canvas.home()
    if screenshot is not None:
        window.problems.recheck()
        app.processEvents()
        ok = window.grab().save(screenshot)
        window.design.undo.setClean()
        window.close()
        return 0 if ok else 2
    return app.exec()
