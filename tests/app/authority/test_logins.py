"""Remote logins (app/authority/logins.py): back-off per host, failures journaled throttled, and an
unknown name answered in the time of a wrong password."""

from __future__ import annotations

import statistics
import time
from pathlib import Path

import pytest

from app.authority import Commands, Source
from app.authority.logins import Logins
from app.authority.users import SCRYPT, Scrypt, Users
from netplc.engine import Engine, FakeClock
from netplc.program import parse
from netplc.records import ListSink
from tests.cheap_users import CHEAP


def rig(folder: Path) -> tuple[Logins, ListSink, list[float]]:
    users = Users(folder)
    users.add("olga", "operator", "s3cret", CHEAP)
    sink, mono = ListSink(), [0.0]
    engine = Engine(parse("JMP 0\n"), clock=FakeClock(), sink=sink)
    layer = Commands(engine, sink, role_of=lambda name: users.get(name) and users.get(name).role,
                     monotonic=lambda: mono[0])
    return Logins(lambda: Users(folder), layer, Source.OPCUA, monotonic=lambda: mono[0]), sink, mono


def test_a_host_that_fails_backs_off_and_others_do_not(tmp_path: Path) -> None:
    logins, _sink, mono = rig(tmp_path)
    assert logins.login("olga", "s3cret", "10.0.0.5:4000").role == "operator"
    for _ in range(3):
        assert logins.login("olga", "guess", "10.0.0.5:4000") is None
    # the right password is refused unchecked while the host backs off (1 s after the 3rd failure)
    assert logins.login("olga", "s3cret", "10.0.0.5:4001") is None
    assert logins.login("olga", "s3cret", "10.0.0.6:4000") is not None  # another host is not held
    mono[0] = 1.5
    assert logins.login("olga", "s3cret", "10.0.0.5:4002") is not None
    assert logins.login("olga", "guess", "10.0.0.5:4002") is None  # the 4th failure: 2 s
    mono[0] = 3.0
    assert logins.login("olga", "s3cret", "10.0.0.5:4002") is None
    mono[0] = 3.6
    assert logins.login("olga", "s3cret", "10.0.0.5:4002") is not None
    assert [logins.backoff(n) for n in (2, 3, 4, 5, 20)] == [0, 1, 2, 4, 60]
    mono[0] = 3.6 + 901  # forgotten after a quarter of an hour without a failure
    assert logins.login("olga", "guess", "10.0.0.5:4002") is None
    assert logins.login("olga", "s3cret", "10.0.0.5:4002") is not None


def test_failures_are_journaled_once_per_user_and_host_per_minute(tmp_path: Path) -> None:
    logins, sink, mono = rig(tmp_path)
    for i in range(50):
        logins.login("olga", "guess", f"10.0.0.5:{4000 + i}")
        logins.login("ghost", "guess", f"10.0.0.5:{4000 + i}")
    records = [r for r in sink.records if r.kind == "operator"]
    failed = [r for r in records if "wrong user name or password" in r.text]
    assert [r.source for r in failed] == ["opcua olga@10.0.0.5:4000", "opcua ghost@10.0.0.5:4000"]
    assert all(r.text.startswith("refused log in") for r in records)
    backing_off = [r for r in records if "refused for" in r.text]  # once per name and host too
    assert len(backing_off) == 2 and len(records) == 4
    mono[0] = 120
    logins.login("olga", "guess", "10.0.0.5:5000")
    assert "more refused like it" in sink.records[-1].text


@pytest.mark.parametrize("scrypt", [Scrypt(n=2**12), Scrypt(n=2**11)], ids=["n4096", "n2048"])
def test_an_unknown_name_takes_the_time_of_a_wrong_password(tmp_path: Path, scrypt: Scrypt) -> None:
    """At two costs kept in the file, one twice the other: the stand-in an unknown name is checked
    against follows the file's users (a stand-in of one fixed cost fails the other by 50 % or more;
    the default's own 50 ms are the same scrypt, four times longer)."""
    users = Users(tmp_path)
    users.add("olga", "operator", "s3cret", scrypt)
    users = Users(tmp_path)

    def cost(name: str) -> float:
        """The thread's CPU time of one check: the work done, not the shared machine's wait."""
        t0 = time.thread_time()
        assert users.verify(name, "guess") is None
        return time.thread_time() - t0

    cost("nobody")  # warm up: the stand-in is made once
    pairs = [(cost("nobody"), cost("olga")) for _ in range(7)]  # interleaved, so drift hits both
    unknown = statistics.median(p[0] for p in pairs)
    wrong = statistics.median(p[1] for p in pairs)
    assert wrong > 0.002 * scrypt.work / SCRYPT.work  # scrypt ran, at that cost (~50 ms at the default's)
    assert abs(unknown - wrong) < 0.25 * wrong, (unknown, wrong)
