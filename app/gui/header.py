"""The workstation's one header line: station, what needs the operator, user on duty, date and time.

At 1366x768 every line above the picture costs the forms a twentieth of the screen. The header,
the alarm banner and the health strip used to take three lines, two of them reserved and empty
when there was nothing to say; they are one line now, of a fixed height, so that nothing below
it moves when an alarm comes or goes (ISA-101: the screen does not move under the operator's
hand). Its middle says what needs the operator: the quiet text while nothing does; the
highest-priority unacknowledged alarm (the banner, red) while any is; what is wrong with the
station itself (the health strip, amber: forces active, a node down, NetPlc stopped) beside it,
or in the whole middle while no alarm is shown. The date sits above the time, the role in the
user's tooltip, so that the banner keeps the width to say its alarm whole.
"""

from __future__ import annotations

import time

from PySide6.QtCore import QEvent, QObject
from PySide6.QtWidgets import QFrame, QGridLayout, QHBoxLayout, QLabel, QPushButton, QWidget

from app.gui import words
from app.gui.alarms import AlarmBanner, HealthStrip
from hmi_forms.elements import formats

LINE = 44  # px: the one line, whatever it says
HEALTH_SHARE = 0.25  # of the middle for the health strip while an alarm is shown beside it


class HeaderLine(QFrame):
    def __init__(self, name: str, banner: AlarmBanner, health: HealthStrip, quiet: str,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setObjectName("header")
        self.setFixedHeight(LINE)
        self.banner, self.health = banner, health
        lay = QHBoxLayout(self)
        lay.setContentsMargins(12, 0, 10, 0)
        lay.setSpacing(8)
        title = self.title = QLabel(name)  # a console of a pair says here which station it is on
        title.setObjectName("headerTitle")
        title.setToolTip("NetPlc Station")
        self.quiet = QLabel(quiet)
        self.quiet.setObjectName("quietLine")
        self.middle = QWidget()
        self.middle.setObjectName("headerMiddle")
        grid = QGridLayout(self.middle)
        grid.setContentsMargins(0, 0, 0, 0)
        grid.setHorizontalSpacing(0)
        grid.addWidget(self.quiet, 0, 0, 1, 2)
        grid.addWidget(banner, 0, 0)  # over the quiet text while shown
        grid.addWidget(health, 0, 1)
        grid.setColumnStretch(0, 1)
        self.user = QLabel()
        self.user.setObjectName("headerUser")
        self.login = QPushButton()
        self.login.setObjectName("headerLogin")
        self.clock = QLabel()
        self.clock.setObjectName("headerClock")
        lay.addWidget(title)
        lay.addWidget(self.middle, 1)
        lay.addWidget(self.user)
        lay.addWidget(self.login)
        lay.addWidget(self.clock)
        for strip in (banner, health):
            strip.installEventFilter(self)
        self.tick()
        self.arrange()

    def eventFilter(self, watched: QObject, event: QEvent) -> bool:
        if event.type() in (QEvent.Type.Show, QEvent.Type.Hide):
            self.arrange()
        return False

    def arrange(self) -> None:
        """Share the middle: the banner takes it all, or leaves the health strip a part of it."""
        grid = self.middle.layout()
        assert isinstance(grid, QGridLayout)
        banner, health = not self.banner.isHidden(), not self.health.isHidden()
        if banner and health:
            self.health.setMaximumWidth(int(self.middle.width() * HEALTH_SHARE) or 16_777_215)
            grid.setColumnStretch(1, 0)
        else:
            self.health.setMaximumWidth(16_777_215)
            grid.setColumnStretch(1, 0 if banner else 1)
        grid.setColumnStretch(0, 1 if banner or not health else 0)
        self.quiet.setVisible(not banner and not health)

    def resizeEvent(self, event: object) -> None:
        super().resizeEvent(event)  # type: ignore[arg-type]
        self.arrange()

    def show_user(self, name: str, role: str, *, logged_in: bool) -> None:
        """The name, its role beneath it in a smaller line: the banner keeps the width."""
        self.user.setText(f"{name}\n{words.role(role)}" if name else self.tr("nobody logged in"))
        self.user.setToolTip(f"{name} ({words.role(role)})" if name else "")
        self.login.setText(self.tr("Log out") if logged_in else self.tr("Log in…"))

    def tick(self) -> None:
        """The date above the time, in the console's format (the operator reads the time)."""
        date, _, clock = formats.date_time(time.time()).partition(" ")
        self.clock.setText(f"{date}\n{clock}")
