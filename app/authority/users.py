"""The station's users and roles, and the session of the operator at the workstation.

Roles are ordered, each allowing what the one before allows: viewer (looks), operator (writes and
acknowledges), engineer (runs and stops NetPlc, forces), admin (manages users). Users live in
`users.json` in the station folder (docs/architecture.md section 10), each with a random salt, an
scrypt hash of the password (never the password itself) and the scrypt cost it was made with, so
that a dearer default later leaves the older hashes valid; the file is written whole (a temporary
file replaced atomically) and readable by its owner only.

Qt-free. The session says who is at the workstation (logged in, the default viewer, idle logout);
what that user may do is the command layer's alone to say (`app/authority/layer.py`, from the one
policy table), which the views ask with the session's name.
"""

from __future__ import annotations

import functools
import hashlib
import hmac
import json
import os
import secrets
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import asdict, dataclass
from pathlib import Path

from app.authority.policy import ROLES, VIEWER, rank
from app.scada.words import ENGLISH, Phrase, json_error, phrase
from netplc.problems import Problem, Problems
from netplc.textfile import TextFileError, read_text

USERS_FILE = "users.json"
MAXMEM = 2**27  # bytes scrypt may take for one hash: room for n = 2**17 at r = 8, 8 times the default
__all__ = ["Refused", "Session", "User", "UserError", "Users", "UsersFileError", "rank"]


class UserError(ValueError):
    """A users-file command that cannot be done, in words for whoever typed it: English as an
    exception, in parts (`name`, `values` of app/scada/words.py; "" for a file's problems) for the
    command layer to say it in the station's language."""

    name = ""
    values: Mapping[str, object] = {}

    def __init__(self, name: str, /, **values: object) -> None:
        super().__init__(ENGLISH(name, **values))
        self.name, self.values = name, values


class UsersFileError(UserError, Problems):
    """A users.json that cannot be used: every problem, each naming the file (`check` lists them,
    a start refuses with them); a UserError too, for whoever manages users."""

    def __init__(self, problems: Sequence[str | Problem]) -> None:
        Problems.__init__(self, problems)


class Refused(Exception):
    """A login that failed; the text says why."""


@dataclass(frozen=True)
class Scrypt:
    """The cost of one user's hash (RFC 7914), kept beside it as modular-crypt formats keep theirs:
    a station may raise the default without invalidating the hashes made before."""

    n: int = 2**14
    r: int = 8
    p: int = 1

    @property
    def work(self) -> int:
        return self.n * self.r * self.p

    def usable(self) -> bool:
        """Integers, n a power of two of at least 2 and below 2**(16·r), r and p at least 1, within
        MAXMEM as OpenSSL counts it: what hashlib.scrypt takes."""
        return (all(type(v) is int for v in (self.n, self.r, self.p)) and self.n >= 2
                and not self.n & (self.n - 1) and self.r >= 1 and self.p >= 1
                and 128 * self.r * (self.n + self.p + 2) <= MAXMEM and self.n < 1 << (16 * self.r))

    def digest(self, password: str, salt: bytes) -> str:
        return hashlib.scrypt(password.encode("utf-8"), salt=salt, n=self.n, r=self.r, p=self.p,
                              maxmem=MAXMEM, dklen=32).hex()


SCRYPT = Scrypt()  # RFC 7914's interactive-login cost, ~50 ms per check: what `add` and `passwd` write


@dataclass(frozen=True)
class User:
    name: str
    role: str
    salt: str  # hex
    hash: str  # hex scrypt of the password with the salt
    scrypt: Scrypt = SCRYPT  # the cost the hash was made with (a file without it: the default)

    def check(self, password: str) -> bool:
        return hmac.compare_digest(self.hash, self.scrypt.digest(password, bytes.fromhex(self.salt)))

    def saved(self) -> dict[str, object]:
        """The user as users.json holds it."""
        return {"name": self.name, "role": self.role, "salt": self.salt, "hash": self.hash,
                "scrypt": asdict(self.scrypt)}


def new_user(name: str, role: str, password: str, scrypt: Scrypt = SCRYPT) -> User:
    salt = secrets.token_bytes(16)
    return User(name, role, salt.hex(), scrypt.digest(password, salt), scrypt)


class Users:
    """The users file of one station folder."""

    def __init__(self, folder: Path) -> None:
        self.path = Path(folder) / USERS_FILE
        self.users: dict[str, User] = {}
        if self.path.exists() or self.path.is_symlink():  # a link to nowhere is named by _read
            self.users = _read(self.path)

    def get(self, name: str) -> User | None:
        return self.users.get(name)

    def add(self, name: str, role: str, password: str, scrypt: Scrypt = SCRYPT) -> User:
        """A new user, hashed at `scrypt`'s cost (the default everywhere but in tests, whose users
        guard nothing and whose hashes are a tenth of the suite's time at the default)."""
        name = name.strip()
        if not name:
            raise UserError("user no name")
        if name in self.users:
            raise UserError("user exists", name=name)
        user = self.users[name] = new_user(name, _role(role), _password(password), scrypt)
        self.save()
        return user

    def remove(self, name: str) -> None:
        if self.users.pop(name, None) is None:
            raise UserError("no user", name=name)
        self.save()

    def passwd(self, name: str, password: str) -> None:
        user = self.users.get(name)
        if user is None:
            raise UserError("no user", name=name)
        self.users[name] = new_user(name, user.role, _password(password))  # at today's default cost
        self.save()

    def verify(self, name: str, password: str) -> User | None:
        """The user if the password is theirs. An unknown name costs the same scrypt as a wrong
        password (checked against a stand-in at `dearest`), so the time of a refusal does not tell
        a client which names exist."""
        user = self.users.get(name)
        if user is None:
            _stand_in(self.dearest).check(password)
            return None
        return user if user.check(password) else None

    @property
    def dearest(self) -> Scrypt:
        """The cost of an unknown name's refusal: the dearest among the users (the default in a
        file without users). A user whose hash is cheaper than another's (made before the default
        was raised) is told apart by time until `passwd` hashes it again at the default."""
        return max((u.scrypt for u in self.users.values()), key=lambda s: s.work, default=SCRYPT)

    def save(self) -> None:
        tmp = self.path.with_suffix(".tmp")
        fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600)
        with os.fdopen(fd, "w", encoding="utf-8") as f:
            json.dump({"users": [u.saved() for u in self.users.values()]}, f, indent=1)
        os.replace(tmp, self.path)


@functools.cache
def _stand_in(scrypt: Scrypt) -> User:
    """A user no name leads to, whose check costs what a real user's at `scrypt` does."""
    return new_user("", VIEWER, secrets.token_hex(16), scrypt)


def _role(role: str) -> str:
    if role not in ROLES:
        raise UserError("no such role", role=role, roles=", ".join(ROLES))
    return role


def _password(password: str) -> str:
    if not password:
        raise UserError("empty password")
    return password


def _read(path: Path) -> dict[str, User]:
    """The users of a users file; UsersFileError names every problem (read as every station file
    is: a regular file, with a size limit)."""
    try:
        doc = json.loads(read_text(path, "read users"))
    except TextFileError as e:
        raise UsersFileError([e]) from None
    except json.JSONDecodeError as e:
        raise UsersFileError([Problem(str(path), phrase("users bad json", line=e.lineno, col=e.colno,
                                                        error=json_error(e.msg)), ENGLISH)]) from None
    except (ValueError, RecursionError) as e:  # int() past 4300 digits; nesting past the stack
        raise UsersFileError([Problem(str(path), phrase("users not json", kind=type(e).__name__),
                                      ENGLISH)]) from None
    items = doc.get("users") if isinstance(doc, dict) else None
    if not isinstance(items, list):
        raise UsersFileError([Problem(str(path), phrase("users no list"), ENGLISH)])
    users: dict[str, User] = {}
    problems: list[Problem] = []
    for i, item in enumerate(items):
        user, problem = _user(item)
        name = item.get("name") if isinstance(item, dict) else None
        where = (phrase("users user", file=path, name=name) if isinstance(name, str) and name
                 else f"{path}: users[{i}]")
        if problem:
            problems.append(Problem(where, problem, ENGLISH))
        elif user is not None and user.name in users:
            problems.append(Problem(where, phrase("users twice"), ENGLISH))
        elif user is not None:
            users[user.name] = user
    if problems:
        raise UsersFileError(problems)
    return users


def _user(item: object) -> tuple[User | None, Phrase | None]:
    """One entry of the users file, or what is wrong with it."""
    if not isinstance(item, dict):
        return None, phrase("users not object")
    missing = [k for k in ("name", "role", "salt", "hash") if not isinstance(item.get(k), str) or not item[k]]
    if missing:
        return None, phrase("users missing", keys=", ".join(missing))
    if item["role"] not in ROLES:
        return None, phrase("no such role", role=item["role"], roles=", ".join(ROLES))
    try:
        bytes.fromhex(item["salt"]), bytes.fromhex(item["hash"])
    except ValueError:
        return None, phrase("users not hex")
    cost = item.get("scrypt")
    if "scrypt" not in item:
        scrypt: Scrypt | None = SCRYPT
    else:
        scrypt = Scrypt(**cost) if isinstance(cost, dict) and set(cost) == {"n", "r", "p"} else None
    if scrypt is None or not scrypt.usable():
        return None, phrase("users bad scrypt", mib=MAXMEM >> 20)
    return User(item["name"], item["role"], item["salt"], item["hash"], scrypt), None


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
