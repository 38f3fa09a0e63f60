"""A station killed with SIGKILL while a client writes as fast as it can: every write the client
was told is done has its journal record in the archive (issue 18 item 5)."""

from __future__ import annotations

import os
import signal
import socket
import struct
import subprocess
import sys
import time
from pathlib import Path

import pytest

from tests.netplc.test_modbus_server_limits import MBAP, journaled_values, write_register

HERE = Path(__file__).parent
ROOT = HERE.parents[1]

pytestmark = pytest.mark.skipif(not hasattr(signal, "SIGKILL"), reason="needs POSIX signals")


def acknowledged_until_killed(sock: socket.socket, child: subprocess.Popen[str], seconds: float) -> set[int]:
    """Pipelined FC6 writes of distinct values, 50 at a time; the values answered as done. The
    child is killed with SIGKILL after `seconds`, in the middle of a batch."""
    acked: set[int] = set()
    value, buf = 1, b""
    deadline = time.monotonic() + seconds
    sock.settimeout(5)
    while True:
        batch = range(value, value + 50)
        sock.sendall(b"".join(write_register(v, 1024 + v % 1000, v) for v in batch))
        value += 50
        if time.monotonic() > deadline:
            child.send_signal(signal.SIGKILL)
        answered = 0
        while answered < 50:
            try:
                data = sock.recv(65536)
            except OSError:
                data = b""
            if not data:
                return acked
            buf += data
            while len(buf) >= 7 and len(buf) >= 6 + MBAP.unpack_from(buf)[2]:
                tid, _, length, _ = MBAP.unpack_from(buf)
                pdu, buf = buf[7 : 6 + length], buf[6 + length :]
                answered += 1
                if pdu[0] == 6:
                    assert struct.unpack(">H", pdu[3:5])[0] == tid
                    acked.add(tid)


def test_sigkill_loses_no_acknowledged_write(tmp_path: Path) -> None:
    db = tmp_path / "journal.sqlite"
    env = {**os.environ, "PYTHONPATH": str(ROOT)}
    child = subprocess.Popen([sys.executable, str(HERE / "modbus_child.py"), str(db)],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    try:
        assert child.stdout is not None
        port = int(child.stdout.readline())
        with socket.create_connection(("127.0.0.1", port)) as sock:
            # half a second is over a thousand writes, and the kill lands in a batch as after 1.5 s
            acked = acknowledged_until_killed(sock, child, 0.5)
        child.wait(10)
    finally:
        if child.poll() is None:
            child.kill()
            child.wait(10)
    assert child.returncode == -signal.SIGKILL
    assert len(acked) > 100
    missing = acked - journaled_values(db)
    assert not missing, f"{len(missing)} of {len(acked)} acknowledged writes have no record"
