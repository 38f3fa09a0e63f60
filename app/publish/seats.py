"""The station's seats: the client sessions logged in at its OPC UA endpoint (remote consoles,
Program views, any other client), each with its user, address and since when.

The journal says each one's coming and going (a system record naming user and peer), the
station's status lists them, and `[opcua] max_consoles` bounds them: one more session is refused
(Bad_TooManySessions) and the refusal journaled like every other, naming who was refused.
"""

from __future__ import annotations

import json
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

from asyncua import ua
from asyncua.common.utils import ServiceError

from app.authority import Commands, Reason, Who
from app.scada.words import Journal
from hmi_forms.elements import formats


@dataclass(frozen=True)
class Seat:
    user: str  # "" for an anonymous client (loopback, or a station without users)
    peer: str  # host:port
    since: float  # wall time of the login

    def line(self) -> str:
        return f"{self.user or 'anonymous'}@{self.peer} since {formats.date_time(self.since)}"


class Seats:
    """Sessions by id; taken and left on the server's loop, read from any thread."""

    def __init__(self, limit: int, commands: Commands, journal: Journal,
                 wallclock: Callable[[], float] = time.time) -> None:
        self.limit = limit
        self.commands = commands
        self.journal = journal
        self.wallclock = wallclock
        self._seats: dict[object, Seat] = {}
        self._lock = threading.Lock()

    def check(self, who: Who) -> None:
        """Before a session is activated: refused (journaled) when the station has `limit` already."""
        with self._lock:
            full = len(self._seats) >= self.limit
        if full:
            self.commands.refuse(who, "open a session", "", Reason.BUSY,
                                 self.commands.say("sessions full", n=self.limit))
            raise ServiceError(ua.StatusCodes.BadTooManySessions)

    def take(self, session: object, who: Who) -> None:
        seat = Seat(who.user, who.peer, self.wallclock())
        with self._lock:
            if session in self._seats:
                return  # activated again (a new user token on the same session): kept as it was
            self._seats[session] = seat
            count = len(self._seats)
        self.journal("opcua connected", who=who.name, n=count, most=self.limit)

    def leave(self, session: object) -> None:
        with self._lock:
            seat = self._seats.pop(session, None)
            count = len(self._seats)
        if seat is not None:
            self.journal("opcua disconnected", who=f"{seat.user or 'anonymous'}@{seat.peer}", n=count)

    def sessions(self) -> set[object]:
        with self._lock:
            return set(self._seats)

    def seats(self) -> list[Seat]:
        with self._lock:
            return sorted(self._seats.values(), key=lambda s: s.since)

    def json(self) -> str:
        return json.dumps([{"user": s.user, "peer": s.peer, "since": s.since} for s in self.seats()])
