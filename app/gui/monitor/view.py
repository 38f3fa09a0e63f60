"""The Program view: the STL listing with live states, a watch table, forcing and single scans.

It reads snapshots only (the source's last one), at most REFRESH_MS apart, and repaints only when
a new scan arrived; the listing is a painted scroll area that draws the lines on screen and
nothing else, so a 2,000-line program costs what 40 lines cost (bench/monitor.py measures the
scan time with it open). The view never writes memory itself: writes, forces and single scans go
to its source, which sends them to the station's command layer as the user at the workstation, or
over OPC UA as the user logged in to the station (`main.py monitor opc.tcp://...`): checked,
journaled with the user, answered. Each answer comes back to the GUI thread (`Answers`) and a
refusal is said under the watch table and in the window's status bar; what the user may not do is
greyed, its tooltip saying why, as the station's layer says it (`Acting.denial`: the role it needs
locally; the station's answer over OPC UA, asked again whenever it may have changed).

Over Modbus (`main.py monitor HOST:PORT`) the view is read-only, and says so in a line of its own:
Modbus has no users, so every control that would act is greyed with the reason (source.py), and
the forces count says they are unknown, since the Modbus map cannot show them.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication, QPoint, QRect, Qt, QTimer, Signal
from PySide6.QtGui import QColor, QContextMenuEvent, QFont, QFontMetrics, QMouseEvent, QPainter, QPaintEvent
from PySide6.QtWidgets import (
    QAbstractScrollArea,
    QComboBox,
    QHBoxLayout,
    QHeaderView,
    QInputDialog,
    QLabel,
    QLineEdit,
    QListWidget,
    QListWidgetItem,
    QMenu,
    QPushButton,
    QSizePolicy,
    QSplitter,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.authority import Action, Answer, Refusal, Ticket, write_range
from app.gui import words
from app.gui.bridge import Answers
from app.gui.monitor.listing import (
    FORMATS,
    TERMINATORS,
    Listing,
    Operand,
    WatchItem,
    fmt_value,
    parse_phy,
    parse_value,
    parse_watch,
)
from app.gui.monitor.source import Acting, Source
from app.gui.notice import confirm
from app.gui.rights import Control
from app.gui.status import IDLE, WARN, Pill
from app.scada.forcing import tag_keys
from app.scada.tag import Tag
from netplc.address import fmt_octal
from netplc.forcing import Force, Kind
from netplc.memory import Snapshot
from netplc.program import CONTACTS

logger = logging.getLogger(__name__)

REFRESH_MS = 100  # at most 10 refreshes per second
ON, OFF, FORCED = QColor("#2e7d32"), QColor("#b0b7c0"), QColor("#e65100")
VALUE_CHARS = 34  # the values column (timers, counters, FON operands) before the source text
NO_LISTING = QT_TRANSLATE_NOOP(
    "ProgramMonitor", "No program to list: give it with --program (the program, or the station folder for "
    "its symbols and tags too), or over Modbus name the station folder (main.py monitor STATION); watch "
    "addresses, symbols or tags in the table on the right.")
READ_ONLY_LINE = QT_TRANSLATE_NOOP(
    "ProgramMonitor", "Read-only over Modbus: Modbus has no users, so this monitor only watches. Write, "
    "force and step as a user of the station: over its OPC UA endpoint (main.py monitor "
    "opc.tcp://HOST:PORT/PATH) or at its own workstation. Its forces are unknown here.")

FORCE_QUESTION = QT_TRANSLATE_NOOP(
    "ProgramMonitor", "Force {0} {1}? The program and the nodes no longer change it until it is unforced.")


def tr(text: str) -> str:
    """The Program view's words in the console's language (context ProgramMonitor)."""
    return QCoreApplication.translate("ProgramMonitor", text)


def parse_force(text: str, tag: Tag) -> float:
    """A physical value typed for a force; ValueError, in words, outside the tag's range."""
    value = parse_phy(text, tag)
    lo, hi = write_range(tag)
    if not lo <= value <= hi:
        raise ValueError(f"{tag.name} is not forced: {tag.format(value)} is outside its range "
                         f"{tag.format(lo)} .. {tag.format(hi)}")
    return value


def forced_text(n: int | None) -> str:
    """The forces count; None: the source cannot see them (over Modbus)."""
    if n is None:
        return QCoreApplication.translate("ProgramMonitor", "F: unknown over Modbus")
    return QCoreApplication.translate("ProgramMonitor", "F: {0} forced").format(n)


class ListingView(QAbstractScrollArea):
    """The listing, painted line by line for the visible lines only."""

    row_clicked = Signal(int)

    def __init__(self, listing: Listing, source: Source, parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("listing")
        self.listing = listing
        self.source = source
        self.snapshot: Snapshot | None = None
        self.fmt = "hex"
        self.forced: set[tuple[Kind, int]] = set()
        self.current = -1
        self.marked: set[int] = set()  # found lines and a symbol's uses
        font = QFont("DejaVu Sans Mono", 9)
        self.setFont(font)
        fm = QFontMetrics(font)
        self.char_w = fm.horizontalAdvance("0")
        self.line_h = fm.height() + 3
        self.ascent = fm.ascent() + 1
        self.viewport().setAutoFillBackground(True)
        self.painted_rows = 0  # rows drawn by the last paint (tests and the bench look)
        self._last_shown: tuple = ()
        self._update_range()

    # --- geometry --------------------------------------------------------------------------------

    def visible_rows(self) -> range:
        first = self.verticalScrollBar().value()
        count = self.viewport().height() // self.line_h + 2
        return range(first, min(len(self.listing), first + count))

    def _update_range(self) -> None:
        page = max(1, self.viewport().height() // self.line_h)
        bar = self.verticalScrollBar()
        bar.setRange(0, max(0, len(self.listing) - page))
        bar.setPageStep(page)
        longest = max((len(r.text) for r in self.listing.rows), default=0)
        width = (12 + VALUE_CHARS + longest) * self.char_w
        h = self.horizontalScrollBar()
        h.setRange(0, max(0, width - self.viewport().width()))
        h.setPageStep(self.viewport().width())

    def resizeEvent(self, event: object) -> None:
        super().resizeEvent(event)  # type: ignore[arg-type]
        self._update_range()

    def go_to(self, row: int) -> None:
        """Select `row` and scroll it to the middle of the view when it is not on screen."""
        self.current = row
        if row not in self.visible_rows()[:-2]:
            self.verticalScrollBar().setValue(max(0, row - self.viewport().height() // self.line_h // 2))
        self.viewport().update()

    def row_at(self, y: int) -> int:
        return self.verticalScrollBar().value() + y // self.line_h

    # --- live state ------------------------------------------------------------------------------

    def show_snapshot(self, snapshot: Snapshot, forced: set[tuple[Kind, int]]) -> None:
        """Take a new snapshot; repaint only when what the visible lines show has changed."""
        self.snapshot = snapshot
        self.forced = forced
        shown = self._shown(snapshot)
        if shown != self._last_shown:
            self._last_shown = shown
            self.viewport().update()

    def _shown(self, snap: Snapshot) -> tuple:
        """What the visible lines show (bit, chain result, values), with the scroll position."""
        instrs = self.listing.program.instrs
        out: list[object] = [self.verticalScrollBar().value(), self.fmt, frozenset(self.forced)]
        for i in self.visible_rows():
            index = self.listing.rows[i].instr
            c = instrs[index].c if index is not None else None
            if index is not None and c is not None:
                out += (snap.bits[c], self.listing.chain(snap, index), self._values(index, snap))
        return tuple(out)

    def paintEvent(self, event: QPaintEvent) -> None:
        p = QPainter(self.viewport())
        lh, cw, asc = self.line_h, self.char_w, self.ascent
        x0 = -self.horizontalScrollBar().value()
        width = self.viewport().width()
        snap = self.snapshot
        rows = self.visible_rows()
        if not len(self.listing):
            p.setPen(QColor("#6b7685"))
            flags = Qt.AlignmentFlag.AlignLeft | Qt.AlignmentFlag.AlignTop | Qt.TextFlag.TextWordWrap
            text = f"{self.source.state()}\n\n{tr(NO_LISTING)}"  # what the monitor does: the whole line
            p.drawText(self.viewport().rect().adjusted(12, 12, -12, -12), int(flags), text)
        first = rows.start
        instrs = self.listing.program.instrs
        self.painted_rows = 0
        for i in rows:
            row = self.listing.rows[i]
            y = (i - first) * lh
            if i == self.current:
                p.fillRect(0, y, width, lh, QColor("#cfe0fb"))
            elif i in self.marked:
                p.fillRect(0, y, width, lh, QColor("#fff3c4"))
            p.setPen(QColor("#8a94a3"))
            p.drawText(x0 + 2, y + asc, f"{row.line:5d}")
            if row.instr is not None and snap is not None:
                ins = instrs[row.instr]
                if ins.c is not None:
                    bit = snap.get_bit(ins.c) if ins.c < len(snap.bits) else 0
                    self._cell(p, x0 + 6 * cw, y, str(bit), ON if bit else OFF, ("bit", ins.c) in self.forced)
                if ins.op in CONTACTS or ins.op in TERMINATORS:
                    res = self.listing.chain(snap, row.instr)
                    self._cell(p, x0 + 9 * cw, y, "\u25b6" if res else "\u00b7", ON if res else OFF, False)
                p.setPen(QColor("#1d4f91"))
                p.drawText(x0 + 12 * cw, y + asc, self._values(row.instr, snap)[:VALUE_CHARS - 1])
            p.setPen(QColor("#263445") if row.instr is not None else QColor("#6b7685"))
            p.drawText(x0 + (12 + VALUE_CHARS) * cw, y + asc, row.text)
            self.painted_rows += 1
        p.end()

    def _cell(self, p: QPainter, x: int, y: int, text: str, colour: QColor, forced: bool) -> None:
        rect = QRect(x, y + 1, 2 * self.char_w + 2, self.line_h - 2)
        p.fillRect(rect, FORCED if forced else colour)
        p.setPen(QColor("#ffffff"))
        p.drawText(rect, Qt.AlignmentFlag.AlignCenter, "F" if forced else text)

    def _values(self, index: int, snap: Snapshot) -> str:
        ins = self.listing.program.instrs[index]
        c = ins.c
        if c is None:
            return ""
        if ins.op == "TIM":
            t = self.source.timer(c)
            now = "--" if t is None else f"{t:.1f}"
            return f"T {now}/{ins.n}  Q={snap.get_bit(c + 1)}"
        if ins.op == "CTR":
            v = self.source.counter(c)
            return f"C {'--' if v is None else v}/{ins.n}  R={snap.get_bit(c + 1)} Q={snap.get_bit(c + 2)}"
        if ins.op == "FON":
            outs = "".join(str(snap.get_bit(c + k)) for k in (1, 2, 3))
            words = " ".join(f"{op.role}={self._word(op, snap)}" for op in self.listing.operands[index][1:])
            return f"out {outs} {words}"
        return ""

    def _word(self, op: Operand, snap: Snapshot) -> str:
        try:
            text = fmt_value(op.read(snap), self.fmt)
        except ValueError:
            return "?"
        return text + ("F" if ("word", op.addr) in self.forced else "")

    # --- mouse -----------------------------------------------------------------------------------

    def mousePressEvent(self, event: QMouseEvent) -> None:
        row = self.row_at(int(event.position().y()))
        if 0 <= row < len(self.listing):
            self.current = row
            self.viewport().update()
            self.row_clicked.emit(row)

    def contextMenuEvent(self, event: QContextMenuEvent) -> None:
        row = self.row_at(event.pos().y())
        if 0 <= row < len(self.listing):
            self.current = row
            self.row_clicked.emit(row)
            monitor = self.parent()
            while monitor is not None and not isinstance(monitor, ProgramMonitor):
                monitor = monitor.parent()
            if monitor is not None:
                monitor.row_menu(row, event.globalPos())


class ProgramMonitor(QWidget):
    """The Program view for one source (local runtime or remote station)."""

    said = Signal(str)  # a refusal or a bad entry, as said under the watch table

    def __init__(self, source: Source, user: Callable[[], str], parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("programMonitor")
        self.source = source
        self.user = user
        self.listing = Listing(source.program)
        self.watch_items: list[WatchItem] = []
        self._last: Snapshot | None = None
        self.refreshes = 0  # views refreshed from a new snapshot (tests and the bench look)
        self.answers = Answers()
        self.answers.answered.connect(self._answered)
        self.acting = source.acting
        self.granted: list[tuple[Control, Action, str]] = []  # controls enabled while the user may act
        self._rights = -1  # the source's `rights` the controls show
        self.ask: Callable[[str, str], bool] = self._ask  # a force or unforce is confirmed (tests answer)

        self.find = QLineEdit()
        self.find.setPlaceholderText(self.tr("Find (Enter: next)"))
        self.find.returnPressed.connect(self.find_next)
        self.labels = QComboBox()
        self.labels.addItem(self.tr("Go to label…"))
        self.labels.addItems(sorted(self.listing.labels))
        self.labels.activated.connect(self._label_chosen)
        self.formats = QComboBox()
        self.formats.addItems(list(FORMATS))
        self.formats.currentTextChanged.connect(self._format_changed)
        self.step_button = QPushButton(self.tr("Step one scan"))
        self.step_button.clicked.connect(self.step)
        self.unforce_button = QPushButton(self.tr("Unforce all"))
        self.unforce_button.clicked.connect(self.ask_unforce_all)
        self._grant(self.step_button, Action.STEP, self.tr("Step one scan"))
        self._grant(self.unforce_button, Action.UNFORCE, self.tr("Unforce all"))
        self.read_only = QLabel(tr(READ_ONLY_LINE))
        self.read_only.setObjectName("monitorReadOnly")
        self.read_only.setStyleSheet("background: #fff4d6; color: #5d4200; padding: 4px 6px;")
        self.read_only.setWordWrap(True)
        self.read_only.setToolTip(source.read_only)
        self.read_only.setVisible(self.acting is None)
        self.state = QLabel()
        self.state.setObjectName("monitorState")
        # a long link error is cut at the window's edge (whole in the tooltip), never widening it
        self.state.setSizePolicy(QSizePolicy.Policy.Ignored, QSizePolicy.Policy.Preferred)
        self.message = QLabel()  # the last refusal: a bad address, a write the station refused
        self.message.setObjectName("monitorMessage")
        self.message.setStyleSheet("color: #c62828; font-weight: bold;")
        self.message.setWordWrap(True)
        self.forced_pill = Pill(forced_text(0))
        bar = QHBoxLayout()
        bar.setContentsMargins(6, 4, 6, 4)
        bar.addWidget(self.find, 2)
        bar.addWidget(self.labels, 1)
        bar.addWidget(QLabel(self.tr("Words:")))
        bar.addWidget(self.formats)
        bar.addWidget(self.step_button)
        bar.addWidget(self.unforce_button)
        bar.addWidget(self.state, 2)
        bar.addWidget(self.forced_pill)

        self.view = ListingView(self.listing, source)
        self.view.row_clicked.connect(self._row_clicked)
        self.watch = QTableWidget(0, 5)
        self.watch.setObjectName("watch")
        self.watch.setHorizontalHeaderLabels(
            [self.tr("Address / symbol"), self.tr("Value"), "Hex", "BCD", self.tr("Forced")])
        self.watch.horizontalHeader().setSectionResizeMode(0, QHeaderView.ResizeMode.Stretch)
        self.watch.verticalHeader().setVisible(False)
        self.watch.itemChanged.connect(self._watch_edited)
        self.watch.setContextMenuPolicy(Qt.ContextMenuPolicy.CustomContextMenu)
        self.watch.customContextMenuRequested.connect(self._watch_menu)
        self.uses_title = QLabel(self.tr("Uses: click a line to follow its operand"))
        self.uses = QListWidget()
        self.uses.itemActivated.connect(self._use_chosen)
        self.uses.itemClicked.connect(self._use_chosen)
        side = QWidget()
        side_lay = QVBoxLayout(side)
        side_lay.setContentsMargins(0, 0, 0, 0)
        side_lay.addWidget(QLabel(self.tr("Watch: type an address (04000, 040042, 02000:w, 04001:b), a "
                                          "symbol or a tag")))
        side_lay.addWidget(self.watch, 3)
        side_lay.addWidget(self.message)
        side_lay.addWidget(self.uses_title)
        side_lay.addWidget(self.uses, 2)
        split = QSplitter(Qt.Orientation.Horizontal)
        split.addWidget(self.view)
        split.addWidget(side)
        split.setStretchFactor(0, 3)
        split.setStretchFactor(1, 2)
        split.setSizes([820, 520])
        lay = QVBoxLayout(self)
        lay.setContentsMargins(0, 0, 0, 0)
        lay.addWidget(self.read_only)
        lay.addLayout(bar)
        lay.addWidget(split, 1)
        self._add_empty_row()
        self.source.need(op.addr for ops in self.listing.operands for op in ops)

        self.timer = QTimer(self)
        self.timer.setInterval(REFRESH_MS)
        self.timer.timeout.connect(self.refresh)
        self.timer.start()
        self.refresh()

    # --- refresh ---------------------------------------------------------------------------------

    def refresh(self) -> None:
        """Show the source's last snapshot, if it is new (at most every REFRESH_MS)."""
        forces = self.source.forces()
        self.show_forced(None if forces is None else len(forces))
        state = self.source.state()
        if state != self.state.text():
            self.state.setText(state)
            self.state.setToolTip(state)
            if not len(self.listing):
                self.view.viewport().update()  # the empty listing says it too
        acting = self.acting
        if acting is not None and acting.rights != self._rights:
            self.update_rights()  # the station answered anew what the user may do
        snap = self.source.snapshot()
        if snap is None or snap is self._last:
            return
        self._last = snap
        self.refreshes += 1
        known = forces or ()
        self.view.show_snapshot(snap, {f.key for f in known})
        self._refresh_watch(snap, {f.key: f for f in known})

    def show_forced(self, n: int | None) -> None:
        unknown = self.tr("the station's forces are not in the Modbus map: see them at its own workstation")
        why = (unknown if n is None else self.tr("forces in effect: force > program > live") if n
               else self.tr("nothing forced"))
        self.forced_pill.show_value(forced_text(n), WARN if n is None or n else IDLE, why)

    def _refresh_watch(self, snap: Snapshot, forces: dict[tuple[Kind, int], Force]) -> None:
        self.watch.blockSignals(True)
        try:
            for r, item in enumerate(self.watch_items):
                try:
                    texts = self._watch_texts(item, snap, forces)
                except ValueError:
                    continue
                for col, text in enumerate(texts, start=1):
                    cell = self.watch.item(r, col)
                    if cell is not None and cell.text() != text and not self._editing(r, col):
                        cell.setText(text)
        finally:
            self.watch.blockSignals(False)

    @staticmethod
    def _watch_texts(item: WatchItem, snap: Snapshot, forces: dict[tuple[Kind, int], Force]) -> list[str]:
        """Value, hex, BCD and forced columns; a tag's value and force in physical units."""
        if item.tag is not None:
            tag = item.tag
            keys = tag_keys(tag)  # its bit, or its words
            words = [Force(k, a, 0).read(snap) for k, a in keys if k == "word"]
            raw = " ".join(fmt_value(w, "hex") for w in words)
            held = [forces.get(key) for key in keys]
            forced = f"F {tag.format(tag.value(snap))} ({held[0].user})" if all(held) and held[0] else ""
            return [tag.format(tag.value(snap)), raw, "", forced]
        v = Force(item.kind, item.addr, 0).read(snap)
        digits = 2 if item.kind == "byte" else 4
        texts = [str(v), "" if item.kind == "bit" else fmt_value(v, "hex", digits),
                 "" if item.kind == "bit" else fmt_value(v, "BCD", digits)]
        f = forces.get((item.kind, item.addr))
        texts.append(f"F {f.value} ({f.user})" if f else "")
        return texts

    def _editing(self, row: int, col: int) -> bool:
        return self.watch.state() == QTableWidget.State.EditingState and self.watch.currentRow() == row \
            and self.watch.currentColumn() == col

    # --- watch table -----------------------------------------------------------------------------

    def _add_empty_row(self) -> None:
        self.watch.blockSignals(True)
        r = self.watch.rowCount()
        self.watch.insertRow(r)
        self.watch.setItem(r, 0, QTableWidgetItem(""))
        for col in range(1, 5):
            cell = QTableWidgetItem("")
            cell.setFlags(cell.flags() & ~Qt.ItemFlag.ItemIsEditable)
            self.watch.setItem(r, col, cell)
        self.watch.blockSignals(False)

    def add_watch(self, text: str) -> WatchItem:
        """Watch an address or symbol; ValueError says why it cannot be watched."""
        item = parse_watch(text, {**self.source.symbols, **self.listing.program.symbols}, self.source.tags)
        r = len(self.watch_items)
        self.watch_items.append(item)
        self.watch.blockSignals(True)
        self.watch.item(r, 0).setText(text.strip())
        self.watch.item(r, 0).setToolTip(item.where)
        self.watch.blockSignals(False)
        self._show_write(r)
        self._add_empty_row()
        addrs = [a for _, a in tag_keys(item.tag)] if item.tag else [item.addr]
        self.source.need([a >> 3 if item.kind == "bit" and a >= 0o40000 else a for a in addrs])
        self._last = None  # show it at the next refresh
        return item

    def _grant(self, control: Control, action: Action, what: str, keep: bool = True) -> None:
        """Enabled while the user may do `action`, its tooltip saying why not (again at each
        change of user or of the station's answer when `keep`); on a read-only source greyed, its
        tooltip saying why."""
        if self.acting is None:
            control.setEnabled(False)
            control.setToolTip(self.source.read_only)
            return
        if keep:
            self.granted.append((control, action, what))
        self._show_right(control, action, what)

    def _show_right(self, control: Control, action: Action, what: str) -> None:
        assert self.acting is not None
        why = self.acting.denial(action, self.user(), what)
        control.setEnabled(why is None)
        control.setToolTip("" if why is None else self._words(why))

    @staticmethod
    def _words(why: Refusal | str) -> str:
        """A denial in the console's language: the role it needs, or the station's own words."""
        return words.refusal(why) if isinstance(why, Refusal) else why

    def _acts(self) -> Acting:
        """The source to act through; nothing that acts is enabled on a read-only one."""
        if self.acting is None:
            raise RuntimeError(f"{self.source.title}: {self.source.read_only}")
        return self.acting

    def update_rights(self) -> None:
        """After a change of who is at the workstation, or of what the station says the user may
        do: the buttons, and the watched values that may be typed over (a write)."""
        if self.acting is not None:
            self._rights = self.acting.rights
        for control, action, what in self.granted:
            self._show_right(control, action, what)
        for r in range(len(self.watch_items)):
            self._show_write(r)

    def _show_write(self, r: int) -> None:
        item, value = self.watch_items[r], self.watch.item(r, 1)
        acting = self.acting
        how = f"in {item.tag.unit or 'its units'}" if item.tag else "(decimal, 0x1F or 1Fh)"
        if acting is None:
            tip: str | None = self.source.read_only
        else:
            why = acting.denial(Action.WRITE, self.user(), f"write {item.where}", item.tag)
            tip = None if why is None else self._words(why)
        editable = Qt.ItemFlag.ItemIsEditable
        self.watch.blockSignals(True)
        value.setFlags(value.flags() | editable if tip is None else value.flags() & ~editable)
        value.setToolTip(f"type a value {how} to write it: journaled with your name" if tip is None else tip)
        self.watch.blockSignals(False)

    def _watch_edited(self, cell: QTableWidgetItem) -> None:
        r, col = cell.row(), cell.column()
        if col == 0 and r == len(self.watch_items):
            text = cell.text()
            if text.strip():
                try:
                    self.add_watch(text)
                except ValueError as e:
                    self.watch.blockSignals(True)
                    cell.setText("")
                    self.watch.blockSignals(False)
                    self._say(str(e))
        elif col == 1 and r < len(self.watch_items) and self.acting is not None:
            item = self.watch_items[r]
            try:
                if item.tag is None:
                    self.write(item, parse_value(cell.text(), item.kind))
                else:
                    self.write_tag(item, parse_phy(cell.text(), item.tag))
            except ValueError as e:
                self._say(str(e))
            self._last = None

    def write(self, item: WatchItem, value: int) -> Ticket:
        """A write like any operator write: a command, journaled with the user."""
        return self._sent(f"write {item.where}", self._acts().write(item.kind, item.addr, value, self.user()))

    def write_tag(self, item: WatchItem, phy: float) -> Ticket:
        """A tag's physical value, checked against its type and range, journaled in its units."""
        assert item.tag is not None
        return self._sent(f"write {item.tag.name}", self._acts().write_tag(item.tag, phy, self.user()))

    def _sent(self, what: str, ticket: Ticket) -> Ticket:
        return self.answers.follow(what, ticket)

    def _answered(self, what: str, answer: Answer) -> None:
        """A refusal is said until the next command is done (a successful step, write or force
        leaves no stale error behind)."""
        if not answer.ok:
            self._say(self.tr("Refused: ") + words.answer(what, answer))
        elif self.message.text():
            self.message.clear()

    def _watch_menu(self, pos: QPoint) -> None:
        r = self.watch.rowAt(pos.y())
        if not 0 <= r < len(self.watch_items):
            return
        item = self.watch_items[r]
        menu = QMenu(self)
        if item.tag is None:
            self._force_actions(menu, item.kind, item.addr, item.where)
        else:
            self._tag_force_actions(menu, item.tag)
        menu.addSeparator()
        menu.addAction(self.tr("Remove from watch"), lambda: self.remove_watch(r))
        menu.exec(self.watch.viewport().mapToGlobal(pos))

    def remove_watch(self, r: int) -> None:
        del self.watch_items[r]
        self.watch.removeRow(r)

    # --- forcing and stepping ---------------------------------------------------------------------

    def _ask(self, title: str, text: str) -> bool:
        return confirm(self, title, text)

    def _force_actions(self, menu: QMenu, kind: Kind, addr: int, where: str) -> None:
        self._add_force_actions(menu, where, lambda: self.confirm_force(kind, addr, None),
                                lambda: self._ask_force(kind, addr, where),
                                lambda: self.confirm_unforce(kind, addr))

    def _tag_force_actions(self, menu: QMenu, tag: Tag) -> None:
        self._add_force_actions(menu, tag.name, lambda: self.confirm_force_tag(tag, None),
                                lambda: self._ask_force_tag(tag), lambda: self.confirm_unforce_tag(tag))

    def _shown(self, tag: Tag | None, kind: Kind = "word", addr: int = 0) -> str:
        """What the memory holds now, as the view shows it (in the tag's units)."""
        snap = self.source.snapshot()
        if snap is None:
            return self.tr("its value")
        return tag.format(tag.value(snap)) if tag is not None else str(Force(kind, addr, 0).read(snap))

    def confirm_force(self, kind: Kind, addr: int, value: int | None) -> Ticket | None:
        """Force after the engineer confirms: the program and the plant lose this memory."""
        where = Force(kind, addr, 0).where
        to = (self.tr("at its value {0} (bumpless)").format(self._shown(None, kind, addr)) if value is None
              else self.tr("to {0}").format(value))
        if not self.ask(self.tr("Force"), tr(FORCE_QUESTION).format(where, to)):
            return None
        return self.force(kind, addr, value)

    def confirm_force_tag(self, tag: Tag, phy: float | None) -> Ticket | None:
        to = (self.tr("at its value {0} (bumpless)").format(self._shown(tag)) if phy is None
              else self.tr("to {0}").format(tag.format(phy)))
        if not self.ask(self.tr("Force"), tr(FORCE_QUESTION).format(tag.name, to)):
            return None
        return self.force_tag(tag, phy)

    def confirm_unforce(self, kind: Kind, addr: int) -> Ticket | None:
        """Unforce after the engineer confirms, told that the forced value stays in memory."""
        where = Force(kind, addr, 0).where
        if not self.ask(self.tr("Unforce"), self.tr("Unforce {0}?").format(where) + " "
                        + words.unforce_stays(self._shown(None, kind, addr))):
            return None
        return self.unforce(kind, addr)

    def confirm_unforce_tag(self, tag: Tag) -> Ticket | None:
        stays = words.unforce_stays(self._shown(tag))
        if not self.ask(self.tr("Unforce"), self.tr("Unforce {0}?").format(tag.name) + " " + stays):
            return None
        return self.unforce_tag(tag)

    def ask_unforce_all(self) -> Ticket | None:
        """The Unforce all button: asks first, naming how many forces go."""
        forces = self.source.forces() or ()
        if not self.ask(self.tr("Unforce all"), self.tr("Unforce all {0} forces?").format(len(forces)) + " "
                        + words.unforce_stays("")):
            return None
        return self.unforce_all()

    def _add_force_actions(self, menu: QMenu, where: str, bumpless: Callable[[], None],
                           ask: Callable[[], None], release: Callable[[], None]) -> None:
        menu.setToolTipsVisible(True)  # a greyed action says which role it needs, or that all are read-only
        bumpless_text = self.tr("Force {0} at its value (bumpless)").format(where)
        for text, slot, act in ((bumpless_text, bumpless, Action.FORCE),
                                (self.tr("Force {0} to…").format(where), ask, Action.FORCE),
                                (self.tr("Unforce {0}").format(where), release, Action.UNFORCE)):
            self._grant(menu.addAction(text, slot), act, text.rstrip("…"), keep=False)

    def _ask_force_tag(self, tag: Tag) -> None:
        lo, hi = write_range(tag)  # PhyMin..PhyMax where the tag scales, not what its word holds
        question = self.tr("Force {0} to ({1}, {2} .. {3}):").format(
            tag.name, tag.unit or self.tr("value"), tag.format(lo), tag.format(hi))
        text, ok = QInputDialog.getText(self, self.tr("Force"), question)
        if ok:
            try:
                self.confirm_force_tag(tag, parse_force(text, tag))
            except ValueError as e:
                self._say(str(e))

    def force_tag(self, tag: Tag, phy: float | None) -> Ticket:
        """Force a tag's bit or all its words to a physical value, or bumpless with None."""
        return self._sent(f"force {tag.name}", self._acts().force_tag(tag, phy, self.user()))

    def unforce_tag(self, tag: Tag) -> Ticket:
        return self._sent(f"unforce {tag.name}", self._acts().unforce_tag(tag, self.user()))

    def _ask_force(self, kind: Kind, addr: int, where: str) -> None:
        question = self.tr("Force {0} to (decimal, 0x1F or 1Fh):").format(where)
        text, ok = QInputDialog.getText(self, self.tr("Force"), question)
        if ok:
            try:
                self.confirm_force(kind, addr, parse_value(text, kind))
            except ValueError as e:
                self._say(str(e))

    def force(self, kind: Kind, addr: int, value: int | None) -> Ticket:
        where = Force(kind, addr, 0).where
        return self._sent(f"force {where}", self._acts().force(kind, addr, value, self.user()))

    def unforce(self, kind: Kind, addr: int) -> Ticket:
        where = Force(kind, addr, 0).where
        return self._sent(f"unforce {where}", self._acts().unforce(kind, addr, self.user()))

    def unforce_all(self) -> Ticket:
        return self._sent(self.tr("Unforce all"), self._acts().unforce_all(self.user()))

    def step(self) -> Ticket:
        """Step one scan (NetPlc stopped) and show its result at once."""
        ticket = self._sent(self.tr("Step one scan"), self._acts().step(self.user()))
        self.refresh()
        return ticket

    # --- navigation ------------------------------------------------------------------------------

    def find_next(self) -> None:
        text = self.find.text()
        if not text:
            return
        row = self.listing.find(text, self.view.current)
        if row is None:
            self._say(f"{text!r} not found")
            return
        self.view.marked = {row}
        self.view.go_to(row)

    def _label_chosen(self, index: int) -> None:
        if index > 0:
            self.go_to_label(self.labels.itemText(index))
        self.labels.setCurrentIndex(0)

    def go_to_label(self, label: str) -> None:
        self.view.go_to(self.listing.labels[label])

    def _format_changed(self, fmt: str) -> None:
        self.view.fmt = fmt
        self.view.viewport().update()

    def _row_clicked(self, row: int) -> None:
        index = self.listing.rows[row].instr
        ops = self.listing.operands[index] if index is not None else []
        if ops:
            self.follow(ops[0].addr)

    def follow(self, addr: int) -> list[int]:
        """List the lines using `addr` (a symbol's uses) and mark them in the listing."""
        rows = self.listing.uses(addr)
        names = [n for n, a in self.listing.program.symbols.items() if a == addr]
        self.uses_title.setText(self.tr("Uses of {0} ({1}): {2} lines").format(
            " / ".join(names) or fmt_octal(addr), fmt_octal(addr), len(rows)))
        self.uses.clear()
        for row in rows:
            r = self.listing.rows[row]
            item = QListWidgetItem(f"{r.line:5d}  {r.text.strip()}")
            item.setData(Qt.ItemDataRole.UserRole, row)
            self.uses.addItem(item)
        self.view.marked = set(rows)
        self.view.viewport().update()
        return rows

    def _use_chosen(self, item: QListWidgetItem) -> None:
        self.view.go_to(int(item.data(Qt.ItemDataRole.UserRole)))

    def row_menu(self, row: int, where: QPoint) -> None:
        index = self.listing.rows[row].instr
        if index is None:
            return
        menu = QMenu(self)
        for op in self.listing.operands[index]:
            name = op.kind if op.kind == "bit" else f"{op.role} word"
            text = fmt_octal(op.addr) + ("" if op.kind == "bit" else ":w")
            menu.addAction(self.tr("Follow uses of {0} {1}").format(name, fmt_octal(op.addr)),
                           lambda a=op.addr: self.follow(a))
            menu.addAction(self.tr("Watch {0}").format(text), lambda t=text: self.add_watch(t))
            self._force_actions(menu, op.kind, op.addr, text)
            menu.addSeparator()
        menu.exec(where)

    def _say(self, text: str) -> None:
        self.message.setText(text)
        self.said.emit(text)

    def closeEvent(self, event: object) -> None:
        self.timer.stop()
        super().closeEvent(event)  # type: ignore[arg-type]
