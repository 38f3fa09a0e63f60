"""Publishing cycles aligned to the scans: a subscription's cycle ends right after the scan's values
are in the address space, not at a timer of its own. The station's values change once per scan
(its tick); a timer's cycle ends anywhere within the tick, so a value waited in the subscription's
queue half a publishing interval on average (25 ms at the console's 50 ms, 50 ms at 100 ms)
before it left, and a cycle shorter than the tick, which a console asked for to bound that wait,
ended empty half the time.

A cycle still lasts the revised publishing interval on average (Part 4 5.13.1): it ends at the
first scan published at or after half a tick before it is due, or half a tick after it is due when
no scan came (a stopped station still sends its keep-alives on time); the next is due an interval
after the scan that ended it, or after its own time. A cycle shorter than the tick waits at most
half its interval for a scan, so the keep-alives a client counts on come on time. A client that
asks the tick is sent each scan's changes once, as soon as they exist; one that asks a second is
sent a second's changes, at the scan nearest to each second.
"""

from __future__ import annotations

import asyncio
import logging
import time

from asyncua.server.internal_subscription import InternalSubscription

logger = logging.getLogger(__name__)


class ScanClock:
    """The scans as the OPC UA server's loop publishes them; used only on that loop."""

    def __init__(self, tick: float) -> None:
        self.tick = tick  # s
        self._next: asyncio.Future[None] | None = None

    def published(self) -> None:
        """A scan's values are all in the address space: the cycles waiting for one end."""
        future, self._next = self._next, None
        if future is not None and not future.done():
            future.set_result(None)

    async def _scan(self, until: float) -> bool:
        """Until the next scan is published (True) or the monotonic time `until` (False)."""
        if self._next is None:
            self._next = asyncio.get_running_loop().create_future()
        done, _ = await asyncio.wait((self._next,), timeout=max(0.0, until - time.monotonic()))
        return bool(done)

    def align(self, subscription: InternalSubscription) -> None:
        """`subscription`'s cycles (its timer's loop, started by asyncua) end at the scans; one
        with no cycles (a publishing interval of 0: each change sent as it comes) is left so."""
        timer = subscription._task
        if timer is None:
            return
        timer.cancel()
        subscription._task = asyncio.get_running_loop().create_task(self._cycles(subscription))

    async def _cycles(self, subscription: InternalSubscription) -> None:
        period = max(0.0, subscription.data.RevisedPublishingInterval / 1000.0)
        half = min(self.tick, period) / 2  # a cycle shorter than the tick keeps its own time
        try:
            await subscription.publish_results()  # the first cycle at once, as asyncua's loop
            due = time.monotonic() + period
            while not subscription._closing:
                scanned = False
                while await self._scan(due + half):
                    if time.monotonic() >= due - half:
                        scanned = True
                        break
                now = time.monotonic()
                await subscription.publish_results()
                # from the scan that ended it, else on its own time (a late loop catches up once)
                due = now + period if scanned else max(due + period, now)
        except Exception:
            logger.exception("OPC UA: the publishing cycles of subscription %s ended",
                             subscription.data.SubscriptionId)
            raise
