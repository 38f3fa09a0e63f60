"""The login dialog: a user name and a password, checked against the station's users.json.

A wrong entry keeps the dialog open with the reason under the fields; the password is never
shown, logged or kept once checked.
"""

from __future__ import annotations

from collections.abc import Callable

from PySide6.QtWidgets import (
    QComboBox,
    QDialog,
    QDialogButtonBox,
    QFormLayout,
    QLabel,
    QLineEdit,
    QVBoxLayout,
    QWidget,
)

from app.authority.users import Refused


class LoginDialog(QDialog):
    def __init__(self, names: list[str], login: Callable[[str, str], None],
                 parent: QWidget | None = None) -> None:
        """`login(name, password)` logs the user in or raises Refused."""
        super().__init__(parent)
        self._login = login
        self.setWindowTitle(self.tr("Log in"))
        lay = QVBoxLayout(self)
        form = QFormLayout()
        self.name = QComboBox()
        self.name.setEditable(True)
        self.name.addItems(names)
        self.name.setCurrentText("")
        self.password = QLineEdit()
        self.password.setEchoMode(QLineEdit.EchoMode.Password)
        form.addRow(self.tr("User:"), self.name)
        form.addRow(self.tr("Password:"), self.password)
        lay.addLayout(form)
        self.message = QLabel("")
        self.message.setObjectName("loginMessage")
        self.message.setStyleSheet("color: #b71c1c; font-weight: bold;")
        lay.addWidget(self.message)
        ok, cancel = QDialogButtonBox.StandardButton.Ok, QDialogButtonBox.StandardButton.Cancel
        buttons = QDialogButtonBox(ok | cancel)
        buttons.accepted.connect(self.try_login)
        buttons.rejected.connect(self.reject)
        lay.addWidget(buttons)
        if not names:
            self.message.setText(self.tr("This station has no users yet: main.py users add NAME --role ROLE"))

    def try_login(self) -> bool:
        try:
            self._login(self.name.currentText().strip(), self.password.text())
        except Refused as e:
            self.message.setText(str(e))
            self.password.clear()
            return False
        finally:
            self.password.clear()
        self.accept()
        return True
