"""A form at the zoom the operator chose: fit width, fit window, 100 % or a step of Ctrl+wheel.

Forms are drawn for one screen size (the demo's are 1000x760); a 1366x768 screen shows only their
top. The form view is put in a graphics scene and the scene scaled, so every element, plot and
entry field scales alike and clicks still land where they are drawn. The choice is remembered per
form and screen size (app/gui/placement.py) and a fit is kept on every resize.
"""

from __future__ import annotations

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication, QRect, Qt, Signal
from PySide6.QtGui import QColor, QPainter, QResizeEvent, QTransform, QWheelEvent
from PySide6.QtWidgets import QFrame, QGraphicsScene, QGraphicsView, QWidget

# the modes are keys (the settings keep them); the status bar says them translated
FIT_WIDTH = QT_TRANSLATE_NOOP("ZoomArea", "fit width")
FIT_WINDOW = QT_TRANSLATE_NOOP("ZoomArea", "fit window")
ACTUAL = "100 %"
MODES = (FIT_WIDTH, FIT_WINDOW, ACTUAL)
STEP = 1.15  # one notch of Ctrl+wheel, or Ctrl++ / Ctrl+-
LIMITS = (0.25, 4.0)
MARGIN = 8  # px kept around a fitted form


class ZoomArea(QGraphicsView):
    zoomed = Signal(str)  # the mode ("fit width", "fit window", "100 %") or the factor as "85 %"

    def __init__(self, form_view: QWidget, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.form_view = form_view
        scene = QGraphicsScene(self)
        self.proxy = scene.addWidget(form_view)
        self.setScene(scene)
        self.setFrameShape(QFrame.Shape.NoFrame)
        self.setAlignment(Qt.AlignmentFlag.AlignHCenter | Qt.AlignmentFlag.AlignTop)
        self.setBackgroundBrush(QColor("#d9dde3"))
        self.setRenderHint(QPainter.RenderHint.SmoothPixmapTransform)
        self.setViewportUpdateMode(QGraphicsView.ViewportUpdateMode.MinimalViewportUpdate)
        self.mode = FIT_WINDOW
        self.factor = 1.0

    def set_mode(self, mode: str) -> None:
        self.mode = mode
        self._apply()

    def set_factor(self, factor: float) -> None:
        self.mode = ""
        self.factor = min(max(factor, LIMITS[0]), LIMITS[1])
        self._apply()

    def zoom_by(self, steps: float) -> None:
        self.set_factor(self.factor * STEP ** steps)

    def restore(self, saved: str) -> None:
        """A remembered choice: a mode, or a factor like "0.85"."""
        if saved in MODES:
            self.set_mode(saved)
            return
        try:
            self.set_factor(float(saved))
        except ValueError:
            self.set_mode(FIT_WINDOW)

    @property
    def choice(self) -> str:
        """What to remember: the mode, or the factor."""
        return self.mode or f"{self.factor:.3f}"

    def label(self) -> str:
        if self.mode:
            return QCoreApplication.translate("ZoomArea", self.mode)
        return f"{self.factor * 100:.0f} %"

    def _apply(self) -> None:
        w, h = self.form_view.width(), self.form_view.height()
        vw, vh = self.viewport().width() - MARGIN, self.viewport().height() - MARGIN
        bar = self.verticalScrollBar().sizeHint().width()
        if self.mode == FIT_WINDOW:
            self.factor = max(min(vw / w, vh / h), 0.05)
        elif self.mode == FIT_WIDTH:  # the vertical scroll bar it may need is taken off first
            k = vw / w
            self.factor = max((vw - bar) / w if h * k > vh else k, 0.05)
        elif self.mode == ACTUAL:
            self.factor = 1.0
        fits = self.mode in (FIT_WIDTH, FIT_WINDOW)
        self.setHorizontalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff if fits
                                          else Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.setVerticalScrollBarPolicy(Qt.ScrollBarPolicy.ScrollBarAlwaysOff if self.mode == FIT_WINDOW
                                        else Qt.ScrollBarPolicy.ScrollBarAsNeeded)
        self.setTransform(QTransform.fromScale(self.factor, self.factor))
        self.setSceneRect(self.proxy.boundingRect())
        self.zoomed.emit(self.label())

    def shown_rect(self) -> QRect:
        """Where the whole form lies in the viewport's coordinates."""
        return self.mapFromScene(self.proxy.sceneBoundingRect()).boundingRect()

    def cut_off(self) -> bool:
        """Whether some of the form lies outside what the viewport shows."""
        return not self.viewport().rect().contains(self.shown_rect())

    def resizeEvent(self, event: QResizeEvent) -> None:
        super().resizeEvent(event)
        self._apply()

    def wheelEvent(self, event: QWheelEvent) -> None:
        if event.modifiers() & Qt.KeyboardModifier.ControlModifier:
            self.zoom_by(event.angleDelta().y() / 120)
            event.accept()
            return
        super().wheelEvent(event)
