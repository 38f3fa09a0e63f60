"""A running headless station (the demo, copied) with its publishers on free loopback ports."""

from __future__ import annotations

import os
import shutil
import signal
import socket
import subprocess
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

from app.station.config import load_station
from app.station.runtime import Runtime
from tests.app.conftest import copy_demo


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def demo_with(folder: Path, extra: str) -> Runtime:
    """The demo station copied to `folder` (unless there already) with `extra` TOML appended,
    started headless."""
    station = folder if (folder / "station.toml").exists() else copy_demo(folder)
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + extra, encoding="utf-8")
    runtime = Runtime(load_station(station))
    runtime.start()
    return runtime


class Mosquitto:
    """A mosquitto broker of the test's own: a config in a temp folder, a listener bound to
    127.0.0.1 only, started and stopped by PID (and restartable on the same port)."""

    def __init__(self, folder: Path) -> None:
        self.folder = folder
        self.port = free_port()
        self.conf = folder / "mosquitto.conf"
        self.conf.write_text(f"listener {self.port} 127.0.0.1\nallow_anonymous true\npersistence false\n"
                             f"log_dest file {folder / 'mosquitto.log'}\nmax_queued_messages 100000\n",
                             encoding="utf-8")
        self.proc: subprocess.Popen[bytes] | None = None

    @property
    def url(self) -> str:
        return f"mqtt://127.0.0.1:{self.port}"

    def start(self) -> None:
        self.proc = subprocess.Popen([MOSQUITTO or "mosquitto", "-c", str(self.conf)],
                                     stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        deadline = time.monotonic() + 10
        while True:
            try:
                socket.create_connection(("127.0.0.1", self.port), 0.2).close()
                return
            except OSError:
                if time.monotonic() > deadline or self.proc.poll() is not None:
                    raise RuntimeError(f"mosquitto did not start: {self.log()}") from None
                time.sleep(0.05)

    def stop(self) -> None:
        if self.proc is not None and self.proc.poll() is None:
            os.kill(self.proc.pid, signal.SIGTERM)
            self.proc.wait(10)
        self.proc = None

    def log(self) -> str:
        path = self.folder / "mosquitto.log"
        return path.read_text(encoding="utf-8", errors="replace") if path.exists() else ""


MOSQUITTO = shutil.which("mosquitto") or next(
    (p for p in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto") if os.access(p, os.X_OK)), None)


@pytest.fixture
def mosquitto(tmp_path: Path) -> Iterator[Mosquitto]:
    if MOSQUITTO is None:
        pytest.skip("mosquitto is not installed (Debian package 'mosquitto'; .ci/run installs it as root)")
    folder = tmp_path / "broker"
    folder.mkdir()
    broker = Mosquitto(folder)
    broker.start()
    yield broker
    broker.stop()


STATION_URI = "urn:netplc:station:Demo station"


def opcua_client(url: str, user: str | None = None, password: str = "") -> object:
    """An asyncua client of `url`, logged in as `user` (None: anonymous)."""
    from asyncua import Client

    client = Client(url)
    if user is not None:
        client.set_user(user)
        client.set_password(password)
    return client


async def tag_node(client: object, name: str) -> object:
    from asyncua import ua

    ns = await client.get_namespace_index(STATION_URI)  # type: ignore[attr-defined]
    return client.get_node(ua.NodeId(f"Tags.{name}", ns))  # type: ignore[attr-defined]
