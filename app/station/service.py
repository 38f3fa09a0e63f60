"""The headless station as a systemd service (`Type=notify`, resources/systemd/): what it tells
the service manager, over `app/station/notify.py`.

- `READY=1` once the station has started and a first scan has gone all the way through the
  engine's listeners to the station's own feed (`Runtime.watch`): systemd orders the units after
  it (a console, a bridge) only once the station really runs.
- `WATCHDOG=1` every half `WATCHDOG_USEC` (`WatchdogSec=`), and only when scans went through the
  feed since the last one: a scan that hangs (a listener that never returns, a dead engine thread)
  stops the pings while the process lives on, and systemd kills and restarts it
  (`Restart=on-failure`), which a plant's PC would otherwise need a person for.
- `STATUS=` the status line (NetPlc's state, the scan count, the nodes, the records), or that the
  scan is stalled, shown by `systemctl status`.
- `STOPPING=1` as the stop begins, so that the seconds of a clean stop (the last records, the
  final retentive save) are not taken for a hang.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from typing import TYPE_CHECKING

from app.station.notify import Notifier

if TYPE_CHECKING:
    from app.scada.readings import Readings
    from app.station.runtime import Runtime

logger = logging.getLogger(__name__)
TICKS_PER_PING = 2  # a ping period shorter than this many ticks would miss scans that are on time


class Service:
    """Start after `runtime.start()`; `stopping()` before `runtime.stop()`. Does nothing when the
    notifier has no service manager."""

    def __init__(self, runtime: Runtime, notifier: Notifier, status_every: float = 5.0) -> None:
        self.runtime = runtime
        self.notifier = notifier
        watchdog = notifier.watchdog
        self.period = watchdog / 2 if watchdog else status_every
        self.scans = 0  # scans seen through the station's feed (written on the engine thread only)
        self._scanned = threading.Event()  # the first scan came (or the stop)
        self._stop = threading.Event()
        self._unwatch: Callable[[], None] | None = None
        self._thread: threading.Thread | None = None
        tick = runtime.station.tick
        if watchdog and self.period < TICKS_PER_PING * tick:
            logger.warning("WatchdogSec=%g s is short for NetSyncTime=%d ms: scans on time would miss "
                           "pings; give it at least %g s", watchdog, runtime.station.NetSyncTime,
                           2 * TICKS_PER_PING * tick)

    def start(self) -> None:
        if not self.notifier.enabled:
            return
        self._unwatch = self.runtime.watch(self._on_scan, "service manager")
        self._thread = threading.Thread(target=self._run, name="service", daemon=True)
        self._thread.start()

    def _on_scan(self, _readings: Readings) -> None:
        self.scans += 1
        if self.scans == 1:
            self._scanned.set()

    def _run(self) -> None:
        self._scanned.wait()
        if self._stop.is_set():
            return
        self.notifier.send("READY=1", self._status())
        last, seen = self.scans, time.monotonic()
        while not self._stop.wait(self.period):
            scans = self.scans
            if scans != last:
                last, seen = scans, time.monotonic()
                ping = ("WATCHDOG=1",) if self.notifier.watchdog else ()
                self.notifier.send(*ping, self._status())
            else:
                self.notifier.send(f"STATUS=scan stalled: no scan for {time.monotonic() - seen:.1f} s, "
                                   f"after {scans} scans")

    def _status(self) -> str:
        return "STATUS=" + self.runtime.status().line()

    def stopping(self) -> None:
        """The stop begins: no more pings, and the manager is told (before the runtime stops)."""
        if self._thread is None:
            return
        self._stop.set()
        self._scanned.set()
        self._thread.join()
        self._thread = None
        if self._unwatch is not None:
            self._unwatch()
            self._unwatch = None
        self.notifier.send("STOPPING=1", "STATUS=stopping")
