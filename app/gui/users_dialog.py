"""The admin's users dialog: the station's users and roles, added, removed and given new passwords
from the workstation (the same users.json `main.py users` manages). Each change is a command of
the station's command layer (`Commands.manage_users`) as the user on duty at that moment: the
layer checks the role, journals it naming them, or refuses it with the reason, said here. The
passwords never leave app/authority/users.py unhashed.
"""

from __future__ import annotations

import logging
from collections.abc import Callable

from PySide6.QtWidgets import (
    QDialog,
    QHBoxLayout,
    QInputDialog,
    QLabel,
    QLineEdit,
    QPushButton,
    QTableWidget,
    QTableWidgetItem,
    QVBoxLayout,
    QWidget,
)

from app.authority import ROLES, Answer, Commands, Who
from app.authority.users import Users
from app.gui import words
from app.gui.bridge import Answers

logger = logging.getLogger(__name__)


class UsersDialog(QDialog):
    def __init__(self, users: Users, commands: Commands, who: Callable[[], Who],
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.users = users
        self.commands = commands
        self.who = who
        self.answers = Answers()
        self.answers.answered.connect(self._answered)
        self.setWindowTitle(self.tr("Users"))
        self.resize(420, 320)
        lay = QVBoxLayout(self)
        self.table = QTableWidget(0, 2)
        self.table.setHorizontalHeaderLabels([self.tr("User"), self.tr("Role")])
        self.table.horizontalHeader().setStretchLastSection(True)
        lay.addWidget(self.table)
        self.message = QLabel("")
        self.message.setStyleSheet("color: #b71c1c; font-weight: bold;")
        lay.addWidget(self.message)
        row = QHBoxLayout()
        for text, slot in ((self.tr("Add…"), self._ask_add), (self.tr("Remove"), self._ask_remove),
                           (self.tr("Password…"), self._ask_passwd)):
            button = QPushButton(text)
            button.clicked.connect(slot)
            row.addWidget(button)
        lay.addLayout(row)
        self._fill()

    def _fill(self) -> None:
        self.table.setRowCount(0)
        for user in self.users.users.values():
            r = self.table.rowCount()
            self.table.insertRow(r)
            self.table.setItem(r, 0, QTableWidgetItem(user.name))
            self.table.setItem(r, 1, QTableWidgetItem(words.role(user.role)))

    def _do(self, what: str, name: str, change: Callable[[], str]) -> bool:
        """Send the change; False when the layer refused it at once (the reason is shown)."""
        self.message.setText("")
        ticket = self.answers.follow(what, self.commands.manage_users(self.who(), name, change))
        self._fill()
        return not (ticket.done() and not ticket.result().ok)

    def _answered(self, what: str, answer: Answer) -> None:
        if not answer.ok:
            self.message.setText(words.answer(what, answer))

    def add_user(self, name: str, role: str, password: str) -> bool:
        return self._do(self.tr("Add user {0}").format(name), name,
                        lambda: f"user {self.users.add(name, role, password).name} added as {role}")

    def remove_user(self, name: str) -> bool:
        return self._do(self.tr("Remove user {0}").format(name), name,
                        lambda: (self.users.remove(name), f"user {name} removed")[1])

    def set_password(self, name: str, password: str) -> bool:
        return self._do(self.tr("Password of {0}").format(name), name,
                        lambda: (self.users.passwd(name, password), f"password of {name} changed")[1])

    def _selected(self) -> str:
        item = self.table.item(self.table.currentRow(), 0)
        return item.text() if item is not None else ""

    def _ask_add(self) -> None:
        name, ok = QInputDialog.getText(self, self.tr("Add user"), self.tr("Name:"))
        if not ok:
            return
        role, ok = QInputDialog.getItem(self, self.tr("Add user"), self.tr("Role:"), list(ROLES), 1, False)
        if ok and (password := self._ask_password()) is not None:
            self.add_user(name, role, password)

    def _ask_remove(self) -> None:
        if name := self._selected():
            self.remove_user(name)

    def _ask_passwd(self) -> None:
        if (name := self._selected()) and (password := self._ask_password()) is not None:
            self.set_password(name, password)

    def _ask_password(self) -> str | None:
        password, ok = QInputDialog.getText(self, self.tr("Password"), self.tr("Password:"),
                                            QLineEdit.EchoMode.Password)
        return password if ok else None
