"""Test users hashed at a cheap scrypt cost (app/authority/users.py keeps each user's cost beside
its hash): at the default cost (~50 ms of CPU a hash or a check) the test users' hashes and logins
were a tenth of the suite's CPU, and they guard nothing. The tests about the cost itself (that
`main.py users add` writes the default, that an unknown name costs what the file's users cost)
keep it."""

from __future__ import annotations

from pathlib import Path

from app.authority.users import Scrypt, Users, new_user
from app.station.config import DEMO_STATION

CHEAP = Scrypt(n=16, r=8, p=1)  # the smallest power of two that is not a toy: ~0.1 ms


def cheap_demo_users(folder: Path) -> Users:
    """The demo's users in the station `folder` (viewer, operator, engineer, admin, each's password
    its name, as README says) hashed again at CHEAP; a user the test has added or changed is left
    as it is."""
    demo = Users(DEMO_STATION).users
    users = Users(folder)
    for user in list(users.users.values()):
        if demo.get(user.name) == user:
            users.users[user.name] = new_user(user.name, user.role, user.name, CHEAP)
    users.save()
    return users
