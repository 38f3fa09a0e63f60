"""A running headless station (the demo, copied) with its publishers on free loopback ports."""

from __future__ import annotations

import json
import os
import shutil
import signal
import socket
import subprocess
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import paho.mqtt.client as mqtt
import pytest

from app.publish import sparkplug as spb
from app.publish.opcua import application_uri
from app.station.config import load_station
from app.station.runtime import Runtime
from tests.app.conftest import DEMO_NAME, copy_demo
from tests.cheap_users import cheap_demo_users
from tests.netplc.test_exchange import wait_until
from tests.opcua_address_space import FOLDER as _CACHE  # noqa: F401  the run's OPC UA cache from now on
from tests.ports import free_port


def demo_with(folder: Path, extra: str, records: list | None = None, language: str | None = None) -> Runtime:
    """The demo station copied to `folder` (unless there already; in `language` when given, see
    `copy_demo`; its users at the tests' cheap cost) with `extra` TOML appended, started headless;
    its records from the start in `records`."""
    station = folder if (folder / "station.toml").exists() else copy_demo(folder, language)
    cheap_demo_users(station)
    toml = station / "station.toml"
    toml.write_text(toml.read_text(encoding="utf-8") + "\n" + extra, encoding="utf-8")
    runtime = Runtime(load_station(station))
    if records is not None:
        runtime.subscribe(records.append)
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

    def stop(self, sig: int = signal.SIGTERM) -> None:
        """SIGTERM: mosquitto publishes its clients' wills as it shuts down; SIGKILL: it vanishes."""
        if self.proc is not None and self.proc.poll() is None:
            os.kill(self.proc.pid, sig)
            self.proc.wait(10)
        self.proc = None

    def log(self) -> str:
        path = self.folder / "mosquitto.log"
        return path.read_text(encoding="utf-8", errors="replace") if path.exists() else ""


MOSQUITTO = shutil.which("mosquitto") or next(
    (p for p in ("/usr/sbin/mosquitto", "/usr/local/sbin/mosquitto") if os.access(p, os.X_OK)), None)


def _broker(folder: Path) -> Iterator[Mosquitto]:
    if MOSQUITTO is None:
        pytest.skip("mosquitto is not installed (Debian package 'mosquitto'; .ci/run installs it as root)")
    folder.mkdir()
    broker = Mosquitto(folder)
    broker.start()
    yield broker
    broker.stop()


@pytest.fixture
def mosquitto(tmp_path: Path) -> Iterator[Mosquitto]:
    """A broker of the test's own, which it may stop and start."""
    yield from _broker(tmp_path / "broker")


@pytest.fixture(scope="module")
def broker(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Mosquitto]:
    """One broker for a module's tests, which leave it running (each its own group and host ids)."""
    yield from _broker(tmp_path_factory.mktemp("mqtt") / "broker")


def mqtt_section(broker: Mosquitto, extra: str = "", group: str = "Plant", writable: str = "TEMP_SP") -> str:
    """[mqtt] of a demo station publishing to `broker` as `group`/Demo, which may write `writable`."""
    return (f'[mqtt]\nenabled = true\nbroker = "{broker.url}"\ngroup_id = "{group}"\nedge_node_id = "Demo"\n'
            f'writable = ["{writable}"]\ndeadband = {{ word = 0.0 }}\n{extra}')


SEQUENCED = ("DBIRTH", "NDATA", "DDATA", "DDEATH")  # after an NBIRTH, one seq counts them all


def metric(payload: Any, name: str) -> Any:
    return next(m for m in payload.metrics if m.name == name)


def props(m: Any) -> dict[str, Any]:
    return dict(zip(m.properties.keys, m.properties.values, strict=True))


def session(host: Host, birth: Any) -> list[tuple[str, str, Any]]:
    """The NBIRTH `birth` and every message of the edge node's session after it that takes a seq
    (up to its NDEATH or the next NBIRTH; commands are the host's)."""
    out = [("NBIRTH", "", birth)]
    for kind, device, payload in host.since(birth):
        if kind in ("NBIRTH", "NDEATH"):
            break
        if kind in SEQUENCED:
            out.append((kind, device, payload))
    return out


class Host:
    """A Sparkplug host application of one group: every message, decoded, in arrival order, as
    (message type, device id or "", payload); it sends commands and, retained, a STATE. With
    `primary` it is that Primary Host Application as spec 3.0 has one connect: its offline STATE
    the will, and on every connection, once subscribed, its online STATE (one timestamp for both:
    paho reconnects with the will it has)."""

    def __init__(self, broker: Mosquitto, group: str = "Plant", edge: str = "Demo",
                 primary: str = "") -> None:
        self.group, self.edge, self.primary = group, edge, primary
        self.messages: list[tuple[str, str, Any]] = []
        self.lock = threading.Lock()
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"host-{group}-{id(self)}")
        client.on_connect = self._connected
        client.on_message = self._message
        subscribed = threading.Event()
        client.on_subscribe = lambda *_: subscribed.set()  # the broker's SUBACK
        self.since_ms = int(time.time() * 1000)
        if primary:
            offline = json.dumps({"online": False, "timestamp": self.since_ms}).encode()
            client.will_set(f"spBv1.0/STATE/{primary}", offline, qos=1, retain=True)
        client.reconnect_delay_set(0.1, 0.5)
        client.connect("127.0.0.1", broker.port)
        client.loop_start()
        self.client = client
        wait_until(subscribed.is_set, 10)  # connected, and the subscription in place

    def _connected(self, client: Any, *_: object) -> None:
        client.subscribe(f"spBv1.0/{self.group}/#", qos=1)
        if self.primary:  # after the subscription, in order; the will was set before connecting
            online = json.dumps({"online": True, "timestamp": self.since_ms}).encode()
            client.publish(f"spBv1.0/STATE/{self.primary}", online, qos=1, retain=True)

    def _message(self, client: Any, userdata: object, message: Any) -> None:
        parts = message.topic.split("/")  # spBv1.0/group/TYPE/edge[/device]
        if len(parts) in (4, 5):
            device = parts[4] if len(parts) == 5 else ""
            with self.lock:
                self.messages.append((parts[2], device, spb.Payload.FromString(message.payload)))

    def of(self, kind: str, device: str | None = None) -> list[Any]:
        """The payloads of one message type (of one device, or all)."""
        with self.lock:
            return [p for k, d, p in self.messages if k == kind and device in (None, d)]

    def wait(self, kind: str, cond: Callable[[Any], bool] = lambda p: True, timeout: float = 10,
             after: int = 0, device: str | None = None) -> Any:
        """The first payload of `kind` (of `device`) that meets `cond`, past the first `after`."""
        def found() -> list[Any]:
            return [p for p in self.of(kind, device)[after:] if cond(p)]

        wait_until(lambda: bool(found()), timeout)
        return found()[0]

    def since(self, payload: Any) -> list[tuple[str, str, Any]]:
        """Every message after `payload`."""
        with self.lock:
            pos = next(i for i, (_, _, p) in enumerate(self.messages) if p is payload)
            return self.messages[pos + 1:]

    def command(self, name: str, value: float | bool | str, device: str = "") -> None:
        """An NCMD (a DCMD to `device`) of one metric, by name, a Double unless it says otherwise."""
        payload = spb.Payload(timestamp=int(time.time() * 1000))
        metric = payload.metrics.add(name=name)
        if isinstance(value, bool):
            metric.datatype, metric.boolean_value = spb.BOOLEAN, value
        elif isinstance(value, str):
            metric.datatype, metric.string_value = spb.STRING, value
        else:
            metric.datatype, metric.double_value = spb.DOUBLE, value
        topic = f"spBv1.0/{self.group}/DCMD/{self.edge}/{device}" if device else \
            f"spBv1.0/{self.group}/NCMD/{self.edge}"
        self.client.publish(topic, payload.SerializeToString(), qos=1).wait_for_publish(5)

    def state(self, host_id: str, online: bool, timestamp: int) -> None:
        """A primary host's STATE, retained, as a Sparkplug 3.0 host publishes it."""
        data = json.dumps({"online": online, "timestamp": timestamp}).encode()
        self.client.publish(f"spBv1.0/STATE/{host_id}", data, qos=1, retain=True).wait_for_publish(5)

    def close(self) -> None:
        self.client.disconnect()
        self.client.loop_stop()


STATION_URI = application_uri(DEMO_NAME)  # the demo's namespace: its Russian name percent-encoded


def opcua_client(url: str, user: str | None = None, password: str = "") -> object:
    """An asyncua client of `url`, logged in as `user` (None: anonymous)."""
    from asyncua import Client

    client = Client(url, timeout=30)  # s: a loaded machine connects slowly
    if user is not None:
        client.set_user(user)
        client.set_password(password)
    return client


async def tag_node(client: object, name: str) -> object:
    from asyncua import ua

    ns = await client.get_namespace_index(STATION_URI)  # type: ignore[attr-defined]
    return client.get_node(ua.NodeId(f"Tags.{name}", ns))  # type: ignore[attr-defined]
