"""The console's words for what Qt-free models say in English: roles, alarm priorities and states,
tag qualities, the command layer's refusals.

The models (app/authority/, app/scada/) keep their English words, which the journal, the command
line and the tests read; the console translates them here, as shown, through Qt's translation
mechanism (context "words" of app/gui/i18n/console_*.ts). The markers below list every source
text for the translation files.
"""

from __future__ import annotations

import dataclasses
import logging

from PySide6.QtCore import QT_TRANSLATE_NOOP, QCoreApplication

from app.authority import Answer, Refusal
from app.scada.alarms import PRIORITIES, State

SOURCES = (
    # roles (app/authority/policy.py ROLES)
    QT_TRANSLATE_NOOP("words", "viewer"), QT_TRANSLATE_NOOP("words", "operator"),
    QT_TRANSLATE_NOOP("words", "engineer"), QT_TRANSLATE_NOOP("words", "admin"),
    # alarm priorities (app/scada/alarms.py PRIORITIES)
    QT_TRANSLATE_NOOP("words", "critical"), QT_TRANSLATE_NOOP("words", "high"),
    QT_TRANSLATE_NOOP("words", "medium"), QT_TRANSLATE_NOOP("words", "low"),
    # alarm states (State.word)
    QT_TRANSLATE_NOOP("words", "normal"), QT_TRANSLATE_NOOP("words", "active-unacknowledged"),
    QT_TRANSLATE_NOOP("words", "active-acknowledged"), QT_TRANSLATE_NOOP("words", "returned-unacknowledged"),
    QT_TRANSLATE_NOOP("words", "shelved"), QT_TRANSLATE_NOOP("words", "suppressed"),
    QT_TRANSLATE_NOOP("words", "out-of-service"),
    # tag qualities (app/scada/quality.py Quality.word)
    QT_TRANSLATE_NOOP("words", "good"), QT_TRANSLATE_NOOP("words", "initial"),
    QT_TRANSLATE_NOOP("words", "stale"), QT_TRANSLATE_NOOP("words", "comm-fail"),
    QT_TRANSLATE_NOOP("words", "not running"), QT_TRANSLATE_NOOP("words", "forced"),
    QT_TRANSLATE_NOOP("words", "station unreachable"),
)


def word(english: str) -> str:
    """A model's English word in the console's language (itself when there is no translation)."""
    return QCoreApplication.translate("words", english) if english else english


def role(name: str) -> str:
    return word(name)


def priority(p: int) -> str:
    return word(PRIORITIES.get(p, ""))


def state(s: State) -> str:
    return word(s.word)


logger = logging.getLogger(__name__)


def refusal(why: Refusal) -> str:
    """The refusal's sentence in the console's language, naming the role needed; the action is the
    caller's (already translated or the form's own text)."""
    if not why.user:
        return QCoreApplication.translate("words", "{0}: nobody is logged in ({1} needed)").format(
            why.action, role(why.role))
    if not why.user_role:
        return QCoreApplication.translate("words", "{0}: {1} is no longer a user ({2} needed)").format(
            why.action, why.user, role(why.role))
    return QCoreApplication.translate("words", "{0}: needs the {1} role; {2} is {3}").format(
        why.action, role(why.role), why.user, role(why.user_role))


def unforce_stays(value: str) -> str:
    """What an unforce leaves behind, said before it is done: the station does not restore the
    value from before the force (a PLC's convention: the live writers take over from it)."""
    if not value:
        return QCoreApplication.translate("words", "The memory keeps the forced values until the program, a "
                                                   "node or an operator writes them.")
    return QCoreApplication.translate(
        "words", "The memory keeps {0}, the forced value, until the program, a node or an operator writes it."
    ).format(value)


def answer(what: str, said: Answer) -> str:
    """Why the command layer did not do `what` (the view's words for what it asked): a refusal for
    the role in the console's language, any other reason in the layer's words."""
    if said.refusal is not None:
        return refusal(dataclasses.replace(said.refusal, action=what))
    return f"{what}: {said.text}"
