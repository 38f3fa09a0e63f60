"""Logging in to a station over OPC UA for the remote Program view (`main.py monitor opc.tcp://...`).

The dialog asks who logs in and their password, and does the rest off the GUI thread (a `Worker`):
it asks the station what it offers (discovery), has the user decide whether to trust the station's
certificate the first time (its SHA-1 and SHA-256 fingerprints shown; kept in the user's
`known_stations.json`, app/publish/client.py), refuses a station whose certificate changed since,
and logs in. A refused login is said in the dialog and may be tried again. Given a password (read
from stdin, for scripts), it logs in by itself once the station is known, and closes with the
refusal in `error` if the station says no.
"""

from __future__ import annotations

import logging
from concurrent.futures import Future
from typing import TypeVar

from PySide6.QtWidgets import (
    QDialog,
    QDialogButtonBox,
    QFormLayout,
    QLabel,
    QLineEdit,
    QMessageBox,
    QVBoxLayout,
    QWidget,
)

from app.publish.client import Certificate, KnownStations, LoginError, Offer, StationClient
from hmi_forms.widgets.worker import Worker
from netplc.problems import Problems

logger = logging.getLogger(__name__)

T = TypeVar("T")
WAIT_S = 30.0  # a discovery or a login the station does not answer within this is given up


class LoginDialog(QDialog):
    def __init__(self, client: StationClient, user: str = "", password: str | None = None,
                 parent: QWidget | None = None) -> None:
        super().__init__(parent)
        self.setWindowTitle(f"Log in to {client.url}")
        self.client = client
        self.known = KnownStations(client.folder)
        self.auto = password is not None  # log in by itself, and close on a refusal
        self.error = ""  # why the dialog closed without a login
        self.user = QLineEdit(user)
        self.password = QLineEdit(password or "")
        self.password.setEchoMode(QLineEdit.EchoMode.Password)
        self.message = QLabel(f"asking {client.url} what it offers…")
        self.message.setObjectName("loginMessage")
        self.message.setWordWrap(True)
        self.message.setMinimumHeight(5 * self.message.fontMetrics().height())  # a refusal and what to do
        self.setMinimumWidth(640)
        self.buttons = QDialogButtonBox(QDialogButtonBox.StandardButton.Cancel)
        self.login = self.buttons.addButton("Log in", QDialogButtonBox.ButtonRole.AcceptRole)
        self.login.setEnabled(False)
        self.buttons.accepted.connect(self.log_in)
        self.buttons.rejected.connect(self.reject)
        form = QFormLayout()
        form.addRow("User of the station:", self.user)
        form.addRow("Password:", self.password)
        lay = QVBoxLayout(self)
        intro = QLabel("The monitor acts as this user of the station: the station checks, and journals "
                       "with this name, everything done from it.")
        intro.setWordWrap(True)
        lay.addWidget(intro)
        lay.addLayout(form)
        lay.addWidget(self.message)
        lay.addWidget(self.buttons)
        (self.password if user else self.user).setFocus()
        self.worker = Worker("monitor-login", expected=(LoginError,), parent=self)
        self.worker.answered.connect(self._answered)
        self.worker.failed.connect(self._failed)
        self._discovery = self.worker.submit(lambda: self._within(client.discover(), "discovery"))
        self._login = -1

    def _answered(self, token: int, result: object) -> None:
        if token == self._discovery:
            assert isinstance(result, Offer)
            self._discovered(result)
        elif token == self._login:
            self.accept()

    def _failed(self, token: int, why: str) -> None:
        self.message.setText(why)
        if token == self._login:
            self.login.setEnabled(True)
        if self.auto:
            self._give_up(why)

    def _discovered(self, offer: Offer) -> None:
        certificate = offer.certificate
        if certificate is None:
            self.message.setText(f"{offer.url} is a loopback endpoint without security: log in as a user of "
                                 "the station")
        else:
            try:
                verdict = self.known.verdict(offer.url, certificate)
            except LoginError as e:
                return self._refuse(str(e))
            if verdict == "changed":
                return self._refuse(
                    f"{offer.url} shows another certificate than the one trusted before (now SHA-256 "
                    f"{certificate.sha256}): not logged in. If the station's certificate was made again on "
                    f"purpose, remove its line from {self.known.path} and connect again.")
            if verdict == "new":
                if not self.trust(certificate):
                    return self._refuse("the station's certificate is not trusted: nothing was sent to it")
                self.known.remember(offer.url, certificate)
            self.message.setText(f"{offer.url}: Basic256Sha256 Sign&Encrypt, certificate trusted "
                                 f"({certificate.subject})")
        self.login.setEnabled(True)
        if self.auto:
            self.log_in()

    def trust(self, certificate: Certificate) -> bool:
        """Ask the user whether to trust the station's certificate, the first time it is seen."""
        answer = QMessageBox.question(
            self, "Trust this station?",
            f"{self.client.url} presents the certificate\n\n{certificate.subject}\n"
            f"SHA-1   {certificate.sha1}\nSHA-256 {certificate.sha256}\n\n"
            "Compare the fingerprints with the ones the station's admin reads at the station "
            f"(pki/own/cert.der). Trust it? It is kept in {self.known.path}, and a station showing "
            "another certificate there later is refused.")
        return answer == QMessageBox.StandardButton.Yes

    def log_in(self) -> None:
        user, password = self.user.text().strip(), self.password.text()
        if not user:
            self.message.setText("name a user of the station")
            return
        self.login.setEnabled(False)
        self.message.setText(f"logging in as {user}…")
        self._login = self.worker.submit(lambda: self._within(self.client.open(user, password), "the login"))

    def _within(self, future: Future[T], what: str) -> T:
        """On the worker's thread: the station's answer, or LoginError after WAIT_S."""
        try:
            return future.result(WAIT_S)
        except TimeoutError:
            raise LoginError(f"{self.client.url}: no answer to {what} within {WAIT_S:g} s") from None

    def _refuse(self, why: str) -> None:
        self.message.setText(why)
        self.login.setEnabled(False)
        if self.auto:
            self._give_up(why)

    def _give_up(self, why: str) -> None:
        self.error = why
        self.reject()


def logged_in(client: StationClient, user: str | None = None, password: str | None = None) -> bool:
    """The login dialog for `client`: True once logged in, False when cancelled (the client
    closed); Problems with the station's refusal when it logged in by itself and was refused."""
    dialog = LoginDialog(client, user or "", password)
    if dialog.exec() == QDialog.DialogCode.Accepted:
        return True
    client.close()
    if dialog.error:
        raise Problems([dialog.error])
    return False
