"""The service manager's notification protocol (systemd's sd_notify(3)), in the few lines it takes.

The manager names a datagram socket in `NOTIFY_SOCKET`: a path, or an abstract address when it
starts with '@'; a message is one datagram of newline-separated `KEY=value` lines. With
`WatchdogSec=` it also sets `WATCHDOG_USEC` (and `WATCHDOG_PID`, the process meant). Without
`NOTIFY_SOCKET` nothing is sent: the station runs the same from a terminal.

Our own code rather than a library: systemd documents the protocol as the stable interface (its
sd_notify(3) man page carries a standalone reimplementation and advises against linking
libsystemd for this alone); `sdnotify` on PyPI is this same sendto, with no release for years;
`systemd-python` wraps libsystemd and needs its headers and a compiler to install.
"""

from __future__ import annotations

import logging
import os
import socket
from collections.abc import Mapping

logger = logging.getLogger(__name__)


class Notifier:
    """Sends notifications to the service manager named by `environ` (the process's by default)."""

    def __init__(self, environ: Mapping[str, str] = os.environ) -> None:
        name = environ.get("NOTIFY_SOCKET", "")
        self.address = "\0" + name[1:] if name.startswith("@") else name
        if name and not name.startswith(("@", "/")):  # vsock: and the like are not for us
            logger.warning("NOTIFY_SOCKET=%s is not a Unix socket address: the service manager is not "
                           "notified", name)
            self.address = ""
        usec = environ.get("WATCHDOG_USEC", "")
        pid = environ.get("WATCHDOG_PID", "")
        ours = not pid or pid == str(os.getpid())
        # seconds within which the manager wants a WATCHDOG=1, or None when it watches nothing
        self.watchdog: float | None = int(usec) / 1e6 if usec.isdigit() and int(usec) and ours else None
        self._sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) if self.address else None
        self._failed = False

    @property
    def enabled(self) -> bool:
        return self._sock is not None

    def send(self, *lines: str) -> None:
        """One notification (`READY=1`, `STATUS=...`); a failure is logged once and the station runs on."""
        if self._sock is None:
            return
        try:
            self._sock.sendto("\n".join(lines).encode(), self.address)
        except OSError as e:
            if not self._failed:
                self._failed = True
                logger.warning("the service manager at NOTIFY_SOCKET was not notified: %s", e)
        else:
            self._failed = False

    def close(self) -> None:
        if self._sock is not None:
            self._sock.close()
            self._sock = None
