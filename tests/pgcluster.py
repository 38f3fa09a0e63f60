"""A throwaway PostgreSQL cluster for the plant-archive tests: the Debian package's binaries,
a data folder under /tmp, a free port on 127.0.0.1, the postmaster our own child (stopped by its
PID). initdb refuses to run as root, so as root the cluster belongs to the `postgres` user the
package creates; the reason a cluster cannot be had is what the tests are skipped with.

A cluster's data folder is a copy of one initdb kept beside it (`_template`): initdb is 4 s of
wall time and 1.5 s of CPU, a copy a tenth of that, and each test process (an xdist worker, a
bench) starts a cluster of its own; the copy is what initdb would have written anew. A test
cluster (no fsync: its data is thrown away) lives in /dev/shm where that has room: every
CREATE DATABASE writes 15 MB (the template's blocks and their WAL), which a disk's file system
costs as much system CPU again as the server's own, and its removal unlinks thousands of files.
"""

from __future__ import annotations

import contextlib
import fcntl
import glob
import os
import pwd
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path

import psycopg


def _bin(name: str) -> str | None:
    found = sorted(glob.glob(f"/usr/lib/postgresql/*/bin/{name}"), reverse=True)
    return found[0] if found else shutil.which(name)


SHM = Path("/dev/shm")
SHM_ROOM = 2 << 30  # bytes free for a test cluster in /dev/shm (a container's may have 64 MB)


def _base(durable: bool) -> Path:
    """Where a cluster's folder goes: /dev/shm for a test cluster if it has room, else /tmp (a
    durable one, a benchmark's, is on a disk as a plant archive's is)."""
    if not durable and SHM.is_dir() and os.access(SHM, os.W_OK) and shutil.disk_usage(SHM).free > SHM_ROOM:
        return SHM
    return Path(tempfile.gettempdir())


def _template(initdb: str, user: str | None, base: Path) -> Path:
    """The data folder of one initdb of this PostgreSQL's binaries for `user`, made by the first
    process that needs it (the others wait on its lock) and kept for the next runs; named by the
    binary's path and time, so that an upgraded package makes a new one."""
    stamp = int(os.stat(initdb).st_mtime)
    version = initdb.replace("/", "_").strip("_")
    kept = base / f"netplc-pg-template-{user or os.geteuid()}-{version}-{stamp}"
    with open(f"{kept}.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        if not (kept / "PG_VERSION").exists():
            making = Path(tempfile.mkdtemp(prefix="netplc-pg-initdb-", dir=base))
            if user:
                shutil.chown(making, user)
            done = subprocess.run([initdb, "-D", str(making / "data"), "-U", "postgres", "--auth=trust",
                                   "-E", "UTF8", "--locale=C.UTF-8", "--no-sync"], user=user,
                                  capture_output=True, text=True, check=False)
            if done.returncode != 0:
                shutil.rmtree(making, ignore_errors=True)
                raise RuntimeError(f"initdb failed: {done.stderr.strip()[-500:]}")
            shutil.rmtree(kept, ignore_errors=True)  # a copy of an earlier run cut short
            (making / "data").rename(kept)
            making.rmdir()
    return kept


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


class PgCluster:
    def __init__(self, durable: bool = False) -> None:
        """durable=False: no fsync (tests); True: the server's defaults (benchmarks)."""
        self.durable = durable
        initdb, postgres = _bin("initdb"), _bin("postgres")
        if initdb is None or postgres is None:
            raise RuntimeError("PostgreSQL is not installed (apt-get install postgresql)")
        self.postgres = postgres
        self.user: str | None = None
        if os.geteuid() == 0:
            try:
                pwd.getpwnam("postgres")
            except KeyError:
                raise RuntimeError("running as root and there is no 'postgres' user for initdb") from None
            self.user = "postgres"
        base = _base(durable)
        self.folder = Path(tempfile.mkdtemp(prefix="netplc-pg-", dir=base))
        if self.user:
            shutil.chown(self.folder, self.user)
        self.data = self.folder / "data"
        try:
            template = _template(initdb, self.user, base)
        except RuntimeError:
            shutil.rmtree(self.folder, ignore_errors=True)
            raise
        # cp -a as the cluster's user: its files, modes and the data folder's 0700 kept
        done = subprocess.run(["cp", "-a", str(template), str(self.data)], user=self.user,
                              capture_output=True, text=True, check=False)
        if done.returncode != 0:
            shutil.rmtree(self.folder, ignore_errors=True)
            raise RuntimeError(f"cannot copy the initdb kept in {template}: {done.stderr.strip()[-500:]}")
        self.port = _free_port()
        self.process: subprocess.Popen | None = None

    @property
    def url(self) -> str:
        return f"postgresql://postgres@127.0.0.1:{self.port}/postgres"

    def database_url(self, name: str) -> str:
        return f"postgresql://postgres@127.0.0.1:{self.port}/{name}"

    def start(self) -> None:
        self.process = subprocess.Popen(
            [self.postgres, "-D", str(self.data), "-p", str(self.port), "-c", "listen_addresses=127.0.0.1",
             "-c", f"unix_socket_directories={self.folder}", "-c", "max_connections=50",
             # its dynamic shared memory in its data folder, removed with it: POSIX segments in
             # /dev/shm outlive a cluster stopped by SIGQUIT
             "-c", "dynamic_shared_memory_type=mmap",
             *([] if self.durable else ["-c", "fsync=off", "-c", "synchronous_commit=off",
                                        "-c", "full_page_writes=off"])],
            user=self.user, stdout=subprocess.DEVNULL, stderr=open(self.folder / "log", "ab"))  # noqa: SIM115
        deadline = time.monotonic() + 30
        while True:
            try:
                with psycopg.connect(self.url, connect_timeout=1):
                    return
            except psycopg.OperationalError:
                if self.process.poll() is not None or time.monotonic() > deadline:
                    log = (self.folder / "log").read_text(errors="replace")[-800:]
                    raise RuntimeError(f"postgres did not start: {log}") from None
                time.sleep(0.1)

    def stop(self, sig: signal.Signals = signal.SIGINT) -> None:
        """SIGINT: PostgreSQL's fast shutdown (open transactions are rolled back)."""
        if self.process is not None:
            self.process.send_signal(sig)
            try:
                self.process.wait(30)
            except subprocess.TimeoutExpired:
                self.process.kill()
                self.process.wait()
            self.process = None

    def create_database(self, name: str) -> str:
        with psycopg.connect(self.url, autocommit=True) as con:
            con.execute(f'CREATE DATABASE "{name}"')
        return self.database_url(name)

    def remove(self) -> None:
        """Stopped at once (SIGQUIT: no shutdown checkpoint, the data is thrown away) and deleted."""
        with contextlib.suppress(Exception):
            self.stop(signal.SIGQUIT)
        shutil.rmtree(self.folder, ignore_errors=True)
