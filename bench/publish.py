"""Publisher figures: 10,000 tags changing every 100 ms tick, served over OPC UA and MQTT.

The station side (engine on its 100 ms tick, every data word bumped every scan, the publishers fed
by their engine listener) runs in this process; each client runs in a process of its own, so the
CPU figure is the station's alone:

1. OPC UA: one asyncua client subscribed to all 10,000 tag variables (100 ms publishing
   interval): monitored-item updates per second it receives, the station's CPU, and the scan's
   mean/max time and overruns. Yardstick, same run: a bare asyncua server whose 10,000 variables
   are written in a plain loop every 100 ms, to the same client.
2. MQTT: the Sparkplug B publisher through a real mosquitto (on a free loopback port) to one
   subscriber: metrics per second received and the end-to-end latency, p50/p99, from the scan
   that changed a value (the metric's timestamp) to the subscriber that decoded it. Yardstick,
   same run: raw paho publishing a payload of the same size every 100 ms, and its latency.
Without publishers the same engine gives the scan's own time and CPU ("scan period unaffected").

    .venv/bin/python bench/publish.py [--seconds N]
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from app.authority import Commands
from app.publish.feed import Watch
from app.publish.mqtt import SparkplugPublisher
from app.publish.opcua import OpcUaServer
from app.scada.quality import LinkView, QualityMap
from app.scada.readings import Readings
from app.scada.tag import Tag, TagType
from app.station.config import MqttSettings, OpcUaSettings
from netplc.address import data_address
from netplc.engine import Engine
from netplc.memory import Memory
from netplc.program import parse
from netplc.records import NullSink
from netplc.scheduler import ScanThread

T = TypeVar("T")
TAGS = 10_000
WORDS = 8_000  # data memory holds 8,192 words: tags 8,000.. share words with the first ones
TICK = 0.1


def free_port() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def station() -> tuple[Engine, list[Tag], Commands, Watch]:
    """The engine, its tags, a command layer (nobody may write: the bench only reads) and the
    station's feed of `Readings` (every tag good), as the runtime gives them to its publishers."""
    tags = [Tag(f"T{i:05d}", data_address(2 * (i % WORDS)), TagType.WORD) for i in range(TAGS)]
    program = parse("JMP 0\n")
    engine = Engine(program, tick=TICK, memory=Memory())

    def bump(mem: Memory) -> None:
        words = np.frombuffer(mem.data, dtype="<u2", count=WORDS)
        words += 1

    engine.subscribe(lambda _s: engine.post(bump))  # every word changes in every scan
    quality = QualityMap(program, tags)
    good = np.zeros(len(tags), dtype=np.int8)

    def watch(callback: Callable[[Readings], None]) -> Callable[[], None]:
        return engine.subscribe(lambda snap: callback(Readings(snap, quality, LinkView(), good)))

    return engine, tags, Commands(engine, NullSink(), role_of=lambda _name: None, tags=tags), watch


def cpu_during(fn: Callable[..., T], *args: object) -> tuple[T, float]:
    """`fn(*args)` and this process's CPU % meanwhile."""
    w0, c0 = time.perf_counter(), time.process_time()
    result = fn(*args)
    return result, 100 * (time.process_time() - c0) / (time.perf_counter() - w0)


def run_client(args: list[str]) -> dict:
    proc = subprocess.run([sys.executable, __file__, *args], capture_output=True, text=True, timeout=600)
    if proc.returncode:
        raise SystemExit(proc.stderr)
    return json.loads(proc.stdout.strip().splitlines()[-1])


def scan_line(engine: Engine) -> str:
    s = engine.stats
    return f"scan mean {s.mean_ms:.2f} ms, max {s.max_ms:.2f} ms, {s.overruns} overruns in {s.count} scans"


# --- the station side -------------------------------------------------------------------------

def bench_plain(seconds: float) -> None:
    engine, *_ = station()
    thread = ScanThread(engine, TICK)
    thread.start()
    _, cpu = cpu_during(time.sleep, seconds)
    thread.stop()
    print(f"no publisher (the scan alone): NetPlc CPU {cpu:.0f} %, {scan_line(engine)}")


def bench_opcua(seconds: float) -> None:
    engine, tags, commands, watch = station()
    url = f"opc.tcp://127.0.0.1:{free_port()}/netplc/"
    server = OpcUaServer(settings=OpcUaSettings(enabled=True, endpoint=url), station="Bench",
                         folder=Path(tempfile.mkdtemp()), tags=tags, commands=commands, watch=watch,
                         engine=engine, exchange=None)
    server.start()
    thread = ScanThread(engine, TICK)
    thread.start()
    result, cpu = cpu_during(run_client, ["--opcua-client", url, str(seconds), "Bench"])
    thread.stop()
    server.stop()
    print(f"OPC UA, NetPlc server: {result['rate']:,.0f} monitored-item updates/s to one client "
          f"(subscribed {result['items']:,} items in {result['setup']:.1f} s), station CPU {cpu:.0f} % "
          f"(the client's process measures only the window), {server.feed.skipped} snapshots skipped, "
          f"{scan_line(engine)}")
    bare = asyncio.run(bare_asyncua_rate(seconds))
    print(f"OPC UA yardstick, bare asyncua server written in a loop: {bare:,.0f} updates/s; "
          f"ratio NetPlc/bare {result['rate'] / bare:.2f}")


async def bare_asyncua_rate(seconds: float) -> float:
    from asyncua import Server, ua
    url = f"opc.tcp://127.0.0.1:{free_port()}/bare/"
    server = Server()
    await server.init()
    server.set_endpoint(url)
    server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
    await server.set_application_uri("urn:netplc:station:Bare")
    idx = await server.register_namespace("urn:netplc:station:Bare")
    folder = await server.nodes.objects.add_folder(ua.NodeId("Tags", idx), f"{idx}:Tags")
    ids = []
    for i in range(TAGS):
        nid = ua.NodeId(f"Tags.T{i:05d}", idx)
        await folder.add_variable(nid, f"{idx}:T{i:05d}", ua.Variant(0, ua.VariantType.UInt16))
        ids.append(nid)
    async with server:
        proc = await asyncio.create_subprocess_exec(sys.executable, __file__, "--opcua-client", url,
                                                    str(seconds), "Bare", stdout=asyncio.subprocess.PIPE)
        write = server.iserver.aspace.write_attribute_value
        reading = asyncio.ensure_future(proc.stdout.read())
        n = 0
        while not reading.done():
            t0 = time.perf_counter()
            n += 1
            for k, nid in enumerate(ids):
                if k % 500 == 499:
                    await asyncio.sleep(0)  # as the NetPlc server does: clients are served meanwhile
                value = ua.DataValue(ua.Variant(n & 0xFFFF, ua.VariantType.UInt16))
                await write(nid, ua.AttributeIds.Value, value)
            await asyncio.sleep(max(0.0, TICK - (time.perf_counter() - t0)))
        out = await reading
    return json.loads(out.decode().strip().splitlines()[-1])["rate"]


def bench_mqtt(seconds: float) -> None:
    from tests.app.publish.conftest import MOSQUITTO, Mosquitto
    if MOSQUITTO is None:
        print("MQTT: skipped, mosquitto is not installed")
        return
    broker = Mosquitto(Path(tempfile.mkdtemp()))
    (broker.folder / "mosquitto.conf").write_text(
        broker.conf.read_text() + "message_size_limit 0\nmax_inflight_bytes 0\n", encoding="utf-8")
    broker.start()
    try:
        engine, tags, commands, watch = station()
        settings = MqttSettings(enabled=True, broker=broker.url, group_id="Bench", edge_node_id="B")
        publisher = SparkplugPublisher(settings, "B", tags=tags, commands=commands, watch=watch,
                                       journal=lambda _t: None)
        thread = ScanThread(engine, TICK)
        sub = subprocess.Popen([sys.executable, __file__, "--mqtt-client", str(broker.port), str(seconds),
                                "spBv1.0/Bench/NDATA/B"], stdout=subprocess.PIPE, text=True)
        time.sleep(1.0)  # subscribed
        publisher.start()
        thread.start()
        w0, c0 = time.perf_counter(), time.process_time()
        out, _ = sub.communicate(timeout=seconds * 4 + 60)
        cpu = 100 * (time.process_time() - c0) / (time.perf_counter() - w0)
        thread.stop()
        publisher.stop()
        r = json.loads(out.strip().splitlines()[-1])
        print(f"MQTT, Sparkplug B NDATA: {r['rate']:,.0f} metrics/s through mosquitto "
              f"({r['per_message']:,.0f} metrics per message), "
              f"latency scan->subscriber p50 {r['p50']:.0f} ms, "
              f"p99 {r['p99']:.0f} ms; station CPU {cpu:.0f} %, {publisher.status.dropped} dropped, "
              f"{publisher.feed.skipped} snapshots skipped, {scan_line(engine)}")
        raw = raw_paho(broker.port, seconds, r["bytes"])
        print(f"MQTT yardstick, raw paho payload of the same size ({r['bytes']:,} bytes) every tick: "
              f"latency p50 {raw['p50']:.1f} ms, p99 {raw['p99']:.1f} ms")
    finally:
        broker.stop()


def raw_paho(port: int, seconds: float, size: int) -> dict:
    import paho.mqtt.client as mqtt
    sub = subprocess.Popen([sys.executable, __file__, "--mqtt-client", str(port), str(seconds), "raw/x"],
                           stdout=subprocess.PIPE, text=True)
    time.sleep(1.0)
    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    client.connect("127.0.0.1", port)
    client.loop_start()
    pad = b"\0" * max(0, size - 8)
    while sub.poll() is None:
        client.publish("raw/x", int(time.time() * 1000 * 1000).to_bytes(8, "little") + pad)
        time.sleep(TICK)
    client.loop_stop()
    return json.loads(sub.stdout.read().strip().splitlines()[-1])


# --- the clients (each in its own process) ----------------------------------------------------

async def opcua_client(url: str, seconds: float, station_name: str) -> None:
    from asyncua import Client, ua
    count = 0

    class Handler:
        def datachange_notification(self, node: object, val: object, data: object) -> None:
            nonlocal count
            count += 1

    async with Client(url, timeout=120, watchdog_intervall=60) as client:
        ns = await client.get_namespace_index(f"urn:netplc:station:{station_name}")
        nodes = [client.get_node(ua.NodeId(f"Tags.T{i:05d}", ns)) for i in range(TAGS)]
        t0 = time.perf_counter()
        sub = await client.create_subscription(100, Handler())
        for k in range(0, TAGS, 1000):
            await sub.subscribe_data_change(nodes[k:k + 1000], queuesize=1)
        setup = time.perf_counter() - t0
        await asyncio.sleep(1.0)
        count = 0
        t0 = time.perf_counter()
        await asyncio.sleep(seconds)
        rate = count / (time.perf_counter() - t0)
    print(json.dumps({"rate": rate, "items": len(nodes), "setup": setup}))


def mqtt_client(port: int, seconds: float, topic: str) -> None:
    import paho.mqtt.client as mqtt

    from app.publish.sparkplug import Payload
    latencies: list[float] = []
    metrics = [0]
    sizes = [0]
    start = [0.0]

    def on_message(client: object, userdata: object, message: mqtt.MQTTMessage) -> None:
        now = time.time() * 1000
        if not start[0]:
            start[0] = time.perf_counter()  # from the first message on
            return
        sizes[0] = len(message.payload)
        if topic.startswith("raw"):
            latencies.append(now - int.from_bytes(message.payload[:8], "little") / 1000)
            metrics[0] += 1
            return
        payload = Payload.FromString(message.payload)
        metrics[0] += len(payload.metrics)
        latencies.append(now - payload.metrics[-1].timestamp)

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2)
    client.on_message = on_message
    client.on_connect = lambda c, *_: c.subscribe(topic)
    client.connect("127.0.0.1", port)
    client.loop_start()
    while not start[0]:
        time.sleep(0.01)
    time.sleep(seconds)
    elapsed = time.perf_counter() - start[0]
    client.loop_stop()
    lat = np.array(latencies or [float("nan")])
    n = max(1, len(latencies))
    print(json.dumps({"rate": metrics[0] / elapsed, "p50": float(np.percentile(lat, 50)),
                      "p99": float(np.percentile(lat, 99)), "per_message": metrics[0] / n,
                      "bytes": sizes[0]}))


def main() -> None:
    if len(sys.argv) > 1 and sys.argv[1] == "--opcua-client":
        asyncio.run(opcua_client(sys.argv[2], float(sys.argv[3]), sys.argv[4]))
        return
    if len(sys.argv) > 1 and sys.argv[1] == "--mqtt-client":
        mqtt_client(int(sys.argv[2]), float(sys.argv[3]), sys.argv[4])
        return
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seconds", type=float, default=5.0)
    parser.add_argument("--only", choices=("opcua", "mqtt"))
    args = parser.parse_args()
    os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
    print(f"{TAGS:,} tags, every value changing every {TICK * 1000:.0f} ms tick; {os.cpu_count()} cores")
    bench_plain(args.seconds)
    if args.only != "opcua":
        bench_mqtt(args.seconds)
    if args.only != "mqtt":
        bench_opcua(args.seconds)


if __name__ == "__main__":
    main()
