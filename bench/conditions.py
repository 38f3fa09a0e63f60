"""OPC UA condition figures: the conditions of N alarms built, then a flood of their transitions.

1. Build: N limit alarms (N/2 tags, each with an H and an HH limit) as ExclusiveLevelAlarmType
   conditions in an asyncua server (`Conditions.build`): the time it takes and the memory it adds
   (the process's peak RSS). Yardstick, same run: asyncua's own `instantiate` of one condition.
2. Flood: every alarm comes in one scan: the N transitions are journaled at once (the alarm
   system's sink posts each to the conditions, from another thread, as the runtime's record
   observer does). A client in a process of its own, subscribed at the Server object (i=2253,
   with AlarmConditionType's fields), counts them: the time until it has every event, events per
   second, and the longest time the server's loop went without a turn meanwhile (a 10 ms ticker
   on it).

    .venv/bin/python bench/conditions.py [--alarms N]
"""

from __future__ import annotations

import argparse
import asyncio
import resource
import subprocess
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from asyncua import Server, ua
from asyncua.common.instantiate_util import instantiate

from app.publish.conditions import Conditions
from app.scada.alarms import AlarmSystem
from app.scada.table import TagAlarms, TagTable
from app.scada.tag import Scaling, Tag, TagType
from netplc.address import data_address
from netplc.memory import Memory
from netplc.records import Record


def free_port() -> int:
    import socket
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


# the client: subscribes at i=2253, says so, then prints the wall time it has all N events
CLIENT = """
import asyncio, sys, time
from asyncua import Client, ua

async def main(url, n):
    got, done = [0], asyncio.Event()

    class Handler:
        def event_notification(self, event):
            got[0] += 1
            if got[0] >= n:
                done.set()

    async with Client(url, timeout=30, watchdog_intervall=30) as client:  # busy is not lost
        sub = await client.create_subscription(100, Handler())
        await sub.subscribe_events(client.get_node(ua.ObjectIds.Server), ua.ObjectIds.AlarmConditionType,
                                   queuesize=2 * n)
        print("ready", flush=True)
        await asyncio.wait_for(done.wait(), 600)
        print(time.time(), flush=True)

asyncio.run(main(sys.argv[1], int(sys.argv[2])))
"""


def rss_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


class Posting:
    """The alarm system's sink: each transition's record to the conditions, as the runtime does."""

    def __init__(self) -> None:
        self.conditions: Conditions | None = None

    def put(self, record: Record) -> None:
        if self.conditions is not None:
            self.conditions.post(record)


async def main(alarms: int) -> None:
    tags = [Tag(f"T{i}", data_address(i), TagType.WORD, "%", Scaling(0, 4095, 0, 100), 1, f"tag {i}")
            for i in range(alarms // 2)]
    table = TagTable(tags, {t.name: TagAlarms(hh=95, h=90, priority=2) for t in tags})
    sink = Posting()
    system = AlarmSystem(table, sink=sink)
    url = f"opc.tcp://127.0.0.1:{free_port()}/bench/"
    server = Server()
    await server.init()
    server.set_endpoint(url)
    server.set_security_policy([ua.SecurityPolicyType.NoSecurity])
    idx = await server.register_namespace("urn:bench")
    def name(text: str) -> ua.QualifiedName:
        return ua.QualifiedName(text, idx)

    station = await server.nodes.objects.add_object(ua.NodeId("Station", idx), name("Station"))
    tag_folder = await station.add_folder(ua.NodeId("Tags", idx), name("Tags"))
    sources = {}
    for t in tags:
        var = await tag_folder.add_variable(ua.NodeId(f"Tags.{t.name}", idx), name(t.name), 0.0)
        sources[t.name] = var.nodeid
    plc = await station.add_object(ua.NodeId("NetPlc", idx), name("NetPlc"))
    state = await plc.add_variable(ua.NodeId("NetPlc.State", idx), name("State"), "running")
    folder = await station.add_folder(ua.NodeId("Alarms", idx), name("Alarms"))

    t0 = time.perf_counter()
    level_type = server.get_node(ua.ObjectIds.ExclusiveLevelAlarmType)
    await instantiate(folder, level_type, ua.NodeId("Yardstick", idx), name("Yardstick"))
    yardstick = time.perf_counter() - t0
    conditions = Conditions(None, {}, system.alarms)  # type: ignore[arg-type]  # no methods called here
    before = rss_mb()
    t0 = time.perf_counter()
    await conditions.build(server, idx, folder, station, sources, plc, state.nodeid)
    built = time.perf_counter() - t0
    print(f"build: {alarms} conditions in {built:.2f} s ({built / alarms * 1000:.2f} ms each), "
          f"peak RSS +{rss_mb() - before:.0f} MB; asyncua's instantiate of one: {yardstick * 1000:.0f} ms")
    sink.conditions = conditions

    await server.start()
    gaps: list[float] = []

    async def ticker() -> None:
        last = time.perf_counter()
        while True:
            await asyncio.sleep(0.01)
            now = time.perf_counter()
            gaps.append(now - last)
            last = now

    tick = asyncio.get_running_loop().create_task(ticker())
    client = await asyncio.create_subprocess_exec(sys.executable, "-c", CLIENT, url, str(alarms),
                                                  stdout=subprocess.PIPE, stderr=subprocess.DEVNULL)
    try:
        assert client.stdout is not None
        assert (await client.stdout.readline()).strip() == b"ready"
        memory = Memory()
        for t in tags:
            memory.set_word(t.address, 4095)  # 100 %: above H and HH
        gaps.clear()
        t0 = time.time()
        flood = threading.Thread(target=system.evaluate, args=(memory.snapshot(), t0))
        flood.start()
        flood.join()
        queue = conditions._queue
        assert queue is not None
        while not queue.empty():
            await asyncio.sleep(0.01)
        shown = time.time() - t0
        took = float((await asyncio.wait_for(client.stdout.readline(), 600)).strip()) - t0
        print(f"flood: {alarms} transitions shown by the server within {shown:.2f} s "
              f"({alarms / shown:,.0f}/s); their events at i=2253 in a client process within {took:.2f} s; "
              f"longest turn of the server's loop {max(gaps) * 1000:.0f} ms")
    finally:
        if client.returncode is None:
            client.kill()
        await client.wait()
        tick.cancel()
        await server.stop()


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--alarms", type=int, default=1000)
    asyncio.run(main(parser.parse_args().alarms))
