"""What the user at a seat may use, as the command layer says: a control the user may not use is
disabled, its tooltip naming the role it needs, in the console's language.

No view checks a role itself: each asks the layer (`Commands.denial`) with who is at the seat now,
whenever that changes (log in, log out, user switch, idle logout) and when it builds a control.
A refusal the layer answers after all (a role changed in users.json meanwhile) is said by the
view from the answer, so a stale tooltip never lets anything through.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass

from PySide6.QtGui import QAction
from PySide6.QtWidgets import QWidget

from app.authority import Action, Commands, Who
from app.gui import words

logger = logging.getLogger(__name__)

Control = QWidget | QAction


@dataclass
class Right:
    control: Control
    action: Action
    what: str  # the control's words for what it does, as a refusal names it
    tip: str = ""  # the control's own tooltip while it may be used
    at_least: str | None = None  # a form element's Role: more than the policy asks, never less
    also: Callable[[], bool] | None = None  # another condition for the control to be enabled


class Rights:
    """The controls of one view with the actions they command, for the user `who()` is now: the
    command layer says what that user may do (`Commands.denial`), `also` adds a view's own
    condition (a control that needs a selection, say)."""

    def __init__(self, commands: Commands, who: Callable[[], Who]) -> None:
        self.commands = commands
        self.who = who
        self.rights: list[Right] = []

    def add(self, control: Control, action: Action, what: str, tip: str = "", *,
            at_least: str | None = None, also: Callable[[], bool] | None = None) -> Right:
        """Keep `control` enabled only while the user may do `action` (and `also()` holds)."""
        right = Right(control, action, what, tip, at_least, also)
        self.rights.append(right)
        self.show(right)
        return right

    def update(self) -> None:
        """After any change of who is at the seat."""
        for right in self.rights:
            self.show(right)

    def show(self, right: Right) -> bool:
        """Enable or disable one control, with the role it needs in its tooltip; True if enabled."""
        commands, who = self.commands, self.who()
        why = commands.denial(who, right.action, right.at_least, right.what)
        allowed = why is None and (right.also is None or right.also())
        right.control.setEnabled(allowed)
        right.control.setToolTip(right.tip if why is None else words.refusal(why))
        return allowed
