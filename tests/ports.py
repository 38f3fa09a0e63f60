"""Ports for the servers the tests start: each test names its station's port before the station
binds it, seconds later on a loaded run."""

from __future__ import annotations

import random
import socket
from pathlib import Path

EPHEMERAL = Path("/proc/sys/net/ipv4/ip_local_port_range")
_random = random.SystemRandom()  # not the global generator, which hypothesis seeds alike in every worker


def free_port() -> int:
    """A port free now, for a station to bind later: below the range the OS hands to the local
    ends of connections (a port of that range, free now, may be any connection's end by then:
    "Address already in use" on a busy test run), and at random, so that the workers' stations
    rarely pick the same."""
    low = int(EPHEMERAL.read_text().split()[0]) if EPHEMERAL.exists() else 32768
    while True:
        with socket.socket() as s:
            try:
                s.bind(("127.0.0.1", _random.randrange(10_000, low)))
            except OSError:
                continue  # a station of another test, or a service, listens there
            return s.getsockname()[1]
