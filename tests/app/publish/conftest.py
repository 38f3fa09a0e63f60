"""A running headless station (the demo, copied) with its publishers on free loopback ports."""

from __future__ import annotations

import socket
from pathlib import Path

from app.config import load_station
from app.runtime import Runtime
from tests.app.conftest import copy_demo


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def demo_with(folder: Path, extra: str) -> Runtime:
    """The demo station copied to `folder` with `extra` TOML appended, started headless."""
    station = copy_demo(folder)
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + extra, encoding="utf-8")
    runtime = Runtime(load_station(station))
    runtime.start()
    return runtime
