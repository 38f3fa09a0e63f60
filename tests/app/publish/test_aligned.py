"""A subscription's publishing cycle ends at the first scan published from half a tick before it is
due, not at a timer of its own, and without scans at half a tick after it is due: asyncua's own
InternalSubscription, its keep-alive every cycle, on a loop of the test's. What is asserted is
the order of scans and cycles, never how fast."""

from __future__ import annotations

import asyncio
import time

from asyncua import ua
from asyncua.server.address_space import AddressSpace
from asyncua.server.internal_subscription import InternalSubscription

from app.publish.aligned import ScanClock

TICK = 0.3  # s: the margins of the order asserted are half a tick, on a loaded machine


async def _subscription(interval_ms: float, cycles: list[float]) -> InternalSubscription:
    async def published(_result: ua.PublishResult) -> None:
        cycles.append(time.monotonic())

    data = ua.CreateSubscriptionResult(SubscriptionId=1, RevisedPublishingInterval=interval_ms,
                                       RevisedLifetimeCount=10_000, RevisedMaxKeepAliveCount=1)
    sub = InternalSubscription(data, AddressSpace(), published, ua.NodeId(1))
    await sub.start()
    return sub


async def _settle() -> None:
    for _ in range(5):
        await asyncio.sleep(0)


def test_a_cycle_ends_at_the_scan_nearest_its_time_not_earlier() -> None:
    async def run() -> None:
        clock, cycles = ScanClock(TICK), []
        sub = await _subscription(2 * TICK * 1000, cycles)  # two ticks: every other scan
        clock.align(sub)
        try:
            await _settle()
            assert len(cycles) == 1  # the first cycle at once
            clock.published()  # a scan long before the cycle is due: nothing sent
            await _settle()
            assert len(cycles) == 1
            await asyncio.sleep(2 * TICK - TICK / 2 + 0.02 - (time.monotonic() - cycles[0]))
            assert len(cycles) == 1  # due in less than half a tick, but no scan yet
            clock.published()
            await _settle()
            assert len(cycles) == 2  # the scan ended the cycle, no timer
            await asyncio.sleep(2 * TICK + TICK / 2 + 0.05)
            assert len(cycles) == 3  # no scan: the cycle ended half a tick after it was due
            assert cycles[2] - cycles[1] >= 2 * TICK + TICK / 2
        finally:
            await sub.stop()

    asyncio.run(run())


def test_a_cycle_of_the_tick_ends_at_each_scan_and_stops_with_its_subscription() -> None:
    async def run() -> None:
        clock, cycles = ScanClock(TICK), []
        sub = await _subscription(TICK * 1000, cycles)
        clock.align(sub)
        await _settle()
        for n in range(2, 4):
            await asyncio.sleep(TICK - (time.monotonic() - cycles[-1]) - 0.02)  # a scan a tick on
            clock.published()
            await _settle()
            assert len(cycles) == n
        await sub.stop()
        clock.published()
        await asyncio.sleep(TICK * 2)
        assert len(cycles) == 3

    asyncio.run(run())


def test_a_cycle_shorter_than_the_tick_keeps_its_own_time_between_scans() -> None:
    """A client's 100 ms beside a 1 s tick: its cycles (keep-alives) do not wait for the scans."""
    async def run() -> None:
        clock, cycles = ScanClock(1.0), []
        sub = await _subscription(100.0, cycles)
        clock.align(sub)
        try:
            await asyncio.sleep(0.65)
            assert len(cycles) >= 4, cycles  # about 6; waiting for scans it would be 1 or 2
        finally:
            await sub.stop()

    asyncio.run(run())


def test_a_subscription_without_cycles_is_left_as_it_is() -> None:
    async def run() -> None:
        sub = await _subscription(0.0, [])
        ScanClock(TICK).align(sub)
        assert sub._task is None
        await sub.stop()

    asyncio.run(run())
