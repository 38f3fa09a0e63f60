"""The one role policy of the station: which role each action needs, whoever asks and from wherever.

Roles are ordered, each allowing what the one before allows (viewer looks; operator writes,
acknowledges, shelves and comments on alarms; engineer runs and stops NetPlc, forces, takes alarms
out of service; admin manages users and trusts certificates). Every entry point (the workstation, the Program
view, `main.py monitor`, OPC UA, MQTT, the Modbus server) asks the command layer
(`app/authority/layer.py`), which reads this table and nothing else; none of them checks a role
itself. A form element may ask more than the table does (its `Role`), never less.

Protocols without users (Modbus, MQTT NCMD) act with the role their station.toml section grants
them (`ROLE_OF_SOURCE` by default): what they may write at all is still only what the station
named writable there.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import StrEnum

ROLES = ("viewer", "operator", "engineer", "admin")  # ordered: each allows what the one before does
VIEWER, OPERATOR, ENGINEER, ADMIN = ROLES


class Action(StrEnum):
    WRITE = "write"  # a bit, a word, a tag: setpoints, commands, Modbus and NCMD writes
    ACKNOWLEDGE = "acknowledge"
    SHELVE = "shelve"
    UNSHELVE = "unshelve"
    COMMENT = "comment"  # an operator's comment on an alarm
    SILENCE = "silence"  # the horn: the alarms stay unacknowledged
    OUT_OF_SERVICE = "out of service"  # take an alarm out of service or back (ISA-18.2)
    FORCE = "force"
    UNFORCE = "unforce"
    RUN = "run"  # NetPlc's program
    STOP = "stop"
    STEP = "step"  # one scan while stopped
    QUIT = "quit"  # the whole station
    USERS = "users"  # user administration
    TRUST = "trust"  # trust a client certificate
    INTO_STANDBY = "IntoStandBy"  # hand the primary role of a hot-standby pair to the standby


POLICY: dict[Action, str] = {
    Action.WRITE: OPERATOR,
    Action.ACKNOWLEDGE: OPERATOR,
    Action.SHELVE: OPERATOR,
    Action.UNSHELVE: OPERATOR,
    Action.COMMENT: OPERATOR,
    Action.SILENCE: OPERATOR,
    Action.OUT_OF_SERVICE: ENGINEER,
    Action.FORCE: ENGINEER,
    Action.UNFORCE: ENGINEER,
    Action.RUN: ENGINEER,
    Action.STOP: ENGINEER,
    Action.STEP: ENGINEER,
    Action.QUIT: ENGINEER,
    Action.USERS: ADMIN,
    Action.TRUST: ADMIN,
    Action.INTO_STANDBY: ENGINEER,
}


class Source(StrEnum):
    """Where a command comes from: the journal names it, and each protocol answers in its terms."""

    CONSOLE = "console"  # the workstation: forms, alarm summary and banner, menus
    PROGRAM_VIEW = "program view"  # the online monitor of the local runtime
    MONITOR = "monitor"  # `main.py monitor` of a remote station
    OPCUA = "opcua"
    MQTT = "mqtt"
    MODBUS = "modbus"
    STATION = "station"  # the station itself (RetainForces at start, the partner of a pair)


# the role a user-less protocol acts with unless its station.toml section says otherwise
ROLE_OF_SOURCE: dict[Source, str] = {Source.MODBUS: OPERATOR, Source.MQTT: OPERATOR, Source.STATION: ADMIN}


def rank(role: str) -> int:
    return ROLES.index(role)


def needs(action: Action, at_least: str | None = None) -> str:
    """The role `action` needs; `at_least` (a form element's Role) may raise it, never lower it."""
    role = POLICY[action]
    if at_least is not None and at_least in ROLES and rank(at_least) > rank(role):
        return at_least
    return role


@dataclass(frozen=True)
class Refusal:
    """Why a command is refused for its role, in parts, so the console can say it in its own
    language (app/gui/words.py) and the command layer in the station's (its journal and answers);
    `str()` is the English sentence."""

    action: str
    role: str  # the role the action needs
    user: str = ""  # "" when nobody is logged in
    user_role: str = ""

    def __str__(self) -> str:
        if not self.user and self.user_role:  # a protocol without users (Modbus, NCMD): its role
            return f"{self.action}: needs the {self.role} role; clients with no user act as {self.user_role}"
        if not self.user:
            return f"{self.action}: nobody is logged in ({self.role} needed)"
        if not self.user_role:
            return f"{self.action}: {self.user} is no longer a user ({self.role} needed)"
        return f"{self.action}: needs the {self.role} role; {self.user} is {self.user_role}"


def policy_table() -> str:
    """The policy as a Markdown table (docs/reference/roles.md prints it from here)."""
    rows = [f"| {a.value} | {POLICY[a]} |" for a in Action]
    return "\n".join(["| Action | Needs the role (or higher) |", "|---|---|", *rows])
