"""The station's users and roles, and the session of the operator at the workstation.

Roles are ordered, each allowing what the one before allows: viewer (looks), operator (writes and
acknowledges), engineer (runs and stops NetPlc, forces), admin (manages users). Users live in
`users.json` in the station folder (docs/architecture.md section 10), each with a random salt and
an scrypt hash of the password, never the password itself; the file is written whole (a temporary
file replaced atomically) and readable by its owner only.

Qt-free. The session says who is at the workstation; what that user may do is the command layer's
to say (`app/authority/layer.py`, from the one policy table): `denial` asks it the same way.
"""

from __future__ import annotations

import functools
import hashlib
import hmac
import json
import os
import secrets
import time
from collections.abc import Callable
from dataclasses import asdict, dataclass
from pathlib import Path

from app.authority.policy import ADMIN, ENGINEER, OPERATOR, ROLES, VIEWER, Refusal, rank

USERS_FILE = "users.json"
SCRYPT = {"n": 2**14, "r": 8, "p": 1}  # RFC 7914's interactive-login cost: ~50 ms per check
__all__ = ["ADMIN", "ENGINEER", "OPERATOR", "VIEWER", "Refusal", "Refused", "Session", "User", "UserError",
           "Users", "rank"]


class UserError(ValueError):
    """A users-file command that cannot be done, in words for whoever typed it."""


class Refused(Exception):
    """An action the logged-in user may not do; the text says why."""


def _digest(password: str, salt: bytes) -> str:
    return hashlib.scrypt(password.encode("utf-8"), salt=salt, dklen=32, **SCRYPT).hex()


@dataclass(frozen=True)
class User:
    name: str
    role: str
    salt: str  # hex
    hash: str  # hex scrypt of the password with the salt

    def allows(self, role: str) -> bool:
        return rank(self.role) >= rank(role)

    def check(self, password: str) -> bool:
        return hmac.compare_digest(self.hash, _digest(password, bytes.fromhex(self.salt)))


def new_user(name: str, role: str, password: str) -> User:
    salt = secrets.token_bytes(16)
    return User(name, role, salt.hex(), _digest(password, salt))


class Users:
    """The users file of one station folder."""

    def __init__(self, folder: Path) -> None:
        self.path = Path(folder) / USERS_FILE
        self.users: dict[str, User] = {}
        if self.path.exists():
            self.users = _read(self.path)

    def get(self, name: str) -> User | None:
        return self.users.get(name)

    def add(self, name: str, role: str, password: str) -> User:
        name = name.strip()
        if not name:
            raise UserError("a user needs a name")
        if name in self.users:
            raise UserError(f"user {name!r} exists already (passwd changes the password)")
        user = self.users[name] = new_user(name, _role(role), _password(password))
        self.save()
        return user

    def remove(self, name: str) -> None:
        if self.users.pop(name, None) is None:
            raise UserError(f"no user {name!r}")
        self.save()

    def passwd(self, name: str, password: str) -> None:
        user = self.users.get(name)
        if user is None:
            raise UserError(f"no user {name!r}")
        self.users[name] = new_user(name, user.role, _password(password))
        self.save()

    def verify(self, name: str, password: str) -> User | None:
        """The user if the password is theirs. An unknown name costs the same scrypt as a wrong
        password (checked against a stand-in), so the time of a refusal does not tell a client
        which names exist."""
        user = self.users.get(name)
        if user is None:
            _stand_in().check(password)
            return None
        return user if user.check(password) else None

    def save(self) -> None:
        tmp = self.path.with_suffix(".tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump({"users": [asdict(u) for u in self.users.values()]}, f, indent=1)
        os.replace(tmp, self.path)


@functools.cache
def _stand_in() -> User:
    """A user no name leads to, whose check costs what a real user's does."""
    return new_user("", VIEWER, secrets.token_hex(16))


def _role(role: str) -> str:
    if role not in ROLES:
        raise UserError(f"role {role!r} is not one of {', '.join(ROLES)}")
    return role


def _password(password: str) -> str:
    if not password:
        raise UserError("the password is empty")
    return password


def _read(path: Path) -> dict[str, User]:
    try:
        items = json.loads(path.read_text(encoding="utf-8"))["users"]
        users = {u["name"]: User(u["name"], _role(u["role"]), u["salt"], u["hash"]) for u in items}
    except (OSError, ValueError, KeyError, TypeError) as e:
        raise UserError(f"{path}: not a users file: {e}") from None
    return users


class Session:
    """Who is at the workstation: a logged-in user, else the configured default viewer, else nobody.

    After `idle` seconds without `touch()` the user is logged out again (0: never)."""

    def __init__(self, users: Users, *, default: str = "", idle: float = 0.0,
                 clock: Callable[[], float] = time.monotonic) -> None:
        self.users = users
        self.default = users.get(default) if default else None
        self.idle = idle
        self.clock = clock
        self.user: User | None = None
        self._last = clock()

    @property
    def current(self) -> User | None:
        return self.user or self.default

    @property
    def name(self) -> str:
        """The name journaled with what the session does ("" when nobody is logged in)."""
        user = self.current
        return user.name if user is not None else ""

    def login(self, name: str, password: str) -> User:
        user = self.users.verify(name, password)
        if user is None:
            raise Refused("wrong user name or password")
        self.user = user
        self.touch()
        return user

    def logout(self) -> None:
        self.user = None

    def touch(self) -> None:
        self._last = self.clock()

    def idle_expired(self) -> User | None:
        """Log out a user idle for too long: the user that just was, or None."""
        user = self.user
        if user is None or not self.idle or self.clock() - self._last < self.idle:
            return None
        self.logout()
        return user

    def denial(self, role: str, action: str) -> Refusal | None:
        """Why the session may not do `action`, which needs `role`, in parts; None when it may."""
        user = self.current
        if user is None:
            return Refusal(action, role)
        if not user.allows(role):
            return Refusal(action, role, user.name, user.role)
        return None

    def refusal(self, role: str, action: str) -> str | None:
        """Why the session may not do `action`, which needs `role`; None when it may."""
        why = self.denial(role, action)
        return None if why is None else str(why)

    def require(self, role: str, action: str) -> str:
        """The user's name if the session may do `action`; Refused saying why otherwise."""
        why = self.refusal(role, action)
        if why is not None:
            raise Refused(why)
        return self.name
