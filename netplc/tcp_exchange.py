"""The exchange's Modbus TCP hot path: one thread, one epoll selector over the nodes' non-blocking
sockets (docs/architecture.md section 7 says why it is not asyncio).

Every node keeps one transaction in flight on its own connection, so K nodes are K requests
outstanding at once and one wake-up of the thread serves every answer that has arrived. A read's
frames are built once per instruction (netplc/modbus/frames.py) and sent with only the
transaction id patched; its answer is checked where it lies in the received bytes and only its data
is copied out. Timeouts, reconnect back-off and the idle probe are one timer per node in a heap:
a node's timer is pushed only when its next due time comes earlier than the one it has, so a read
costs no heap entry.

A node's state (netplc/links.py `LinkState`) is touched by this thread only; the engine thread hands
requests over through `submit` (one wake-up per batch), the outcomes go back through the Exchange.
"""

from __future__ import annotations

import contextlib
import errno
import heapq
import ipaddress
import itertools
import logging
import math
import os
import selectors
import socket
import threading
import time
from collections import deque
from collections.abc import Callable
from concurrent.futures import Future, ThreadPoolExecutor
from typing import TYPE_CHECKING

from netplc.links import LinkState, NodeStats, Outcomes, Request, Steps
from netplc.modbus import (
    Block,
    DeviceError,
    Frame,
    FrameError,
    LinkError,
    MapError,
    answer_data,
    frame_size,
)

if TYPE_CHECKING:
    from netplc.exchange import NodeConfig

logger = logging.getLogger(__name__)

READ, WRITE = selectors.EVENT_READ, selectors.EVENT_WRITE
CRASHED = "node %d: request failed inside the exchange"
CONNECTING = (0, errno.EINPROGRESS, errno.EWOULDBLOCK, errno.EAGAIN)
Address = tuple[int, tuple[str, int]]  # socket family, (host, port)


class TcpNode(LinkState):
    """One Modbus TCP node on the hub's thread: its connection, its queue of requests, the request
    being served (a `Steps` generator, the frame in flight and its deadline)."""

    def __init__(self, config: NodeConfig, exchange: Outcomes, stats: NodeStats, hub: TcpHub) -> None:
        super().__init__(config, exchange, stats)
        self.hub = hub
        assert config.parsed is not None
        self.endpoint = config.parsed
        self.timeout = config.timeout
        self.sock: socket.socket | None = None
        self.connecting = False  # the socket is being connected (or its address resolved)
        self.attempt_id = 0  # tells a late address resolution from the one awaited
        self.addresses: list[Address] = []  # the host's further addresses, tried in turn
        self.queue: deque[Request] = deque()
        self.req: Request | None = None  # the request being served
        self.run: Steps | None = None  # None while a one-frame read is served without steps
        self.read_block: Block | None = None  # that read's block
        self.where = ""
        self.attempt = 0
        self.frame: Frame | None = None  # the transaction in flight
        self.tid = 0
        self.deadline = 0.0  # of the transaction or connection in flight; 0: nothing in flight
        self.buf = b""  # the front of a frame that has not all arrived
        self.rest = b""  # what send() could not take yet
        self.timer = math.inf  # the earliest live entry of this node in the hub's heap

    # --- requests --------------------------------------------------------------------------------

    def submit(self, req: Request) -> None:
        self.queue.append(req)
        if self.req is None:
            self.next()

    def next(self) -> None:
        """Serve the queued requests in order until one is in flight; those that come while the
        node backs off fail at once, as do blocks outside the node's map (nothing is sent)."""
        queue = self.queue
        while self.req is None and queue:
            req = queue.popleft()
            if req is not self.probe and self.hub.now < self.retry_at:
                self.finish(req, None, self.stats.last_error or "link down")
                continue
            self.attempt = 0
            plan = req.plan
            if plan is not None and len(plan[2]) == 1:  # the hot path: a one-frame read built before
                self.req, self.read_block, self.where, self.frame = req, plan[0], plan[1], plan[2][0]
                self.transmit()
                continue
            steps, where = self.steps(req)
            if steps is None:
                self.finish(req, None, where)
                continue
            self.req, self.run, self.where = req, steps, where
            self.advance(None)

    def advance(self, answer: bytes | None) -> None:
        """Hand an answer's data to the request's steps: send the next frame, or finish."""
        if self.run is None:  # a one-frame read: its answer is the block
            assert answer is not None and self.read_block is not None
            self.answered()
            self.end(self.read_block.decode_wire(answer), "")
            return
        try:
            frame = self.run.send(answer)  # type: ignore[arg-type]
        except StopIteration as done:
            self.answered()
            self.end(done.value, "")
            return
        except MapError as e:
            self.end(None, self.failed(e, self.where, self.key))
            return
        self.frame = frame
        self.transmit()

    @property
    def key(self) -> int:
        return self.req.key if self.req is not None else -1

    def end(self, data: bytes | None, error: str) -> None:
        """The request is done: its outcome goes to the exchange, the next one starts."""
        req = self.req
        self.req = self.run = self.frame = self.read_block = None
        self.deadline = 0.0
        self.active = now = self.hub.now
        if req is not None:
            self.finish(req, data, error)
        if self.queue:
            self.next()
        if self.req is None and self.timer > now + self.idle:  # the probe's turn: already due earlier?
            self.hub.arm(self, max(now + self.idle, self.retry_at))

    def finish(self, req: Request, data: bytes | None, error: str) -> None:
        if req is not self.probe:
            req.data, req.error = data, error
            self.exchange.complete(self, req)

    def retry(self, error: LinkError) -> None:
        """An attempt failed on the link: the connection is dropped; the request starts over on a
        new one while it has attempts left, else it fails and the link is down."""
        self.close()
        if self.req is None:
            return
        self.attempt += 1
        if self.attempt > self.config.retries:
            self.end(None, self.failed(error, self.where, self.key))
            return
        steps, _ = self.steps(self.req)
        assert steps is not None
        self.run = steps
        self.advance(None)

    def crashed(self, error: Exception) -> None:
        """A bug met while serving: it must not end the node's service, nor show the link up."""
        self.close()
        text = f"internal error: {error!r}"
        self.down(text)
        if self.req is not None:
            self.end(None, text)

    # --- the wire --------------------------------------------------------------------------------

    def transmit(self) -> None:
        if self.sock is None:
            self.connect()  # the frame goes once connected
            return
        frame = self.frame
        assert frame is not None
        self.tid = tid = self.tid % 0xFFFF + 1
        adu = frame.adu  # as Frame.stamped, inline: this is once per read
        adu[0] = tid >> 8
        adu[1] = tid & 0xFF
        self.deadline = deadline = self.hub.now + self.timeout
        if deadline < self.timer:
            self.hub.arm(self, deadline)
        try:
            sent = self.sock.send(adu)
        except BlockingIOError:
            sent = 0
        except OSError as e:
            self.retry(LinkError(f"{frame.what}: connection lost: {e}"))
            return
        if sent < len(adu):
            self.rest = bytes(adu[sent:])
            self.hub.selector.modify(self.sock, READ | WRITE, self)

    def connect(self) -> None:
        self.connecting = True
        self.attempt_id += 1
        self.deadline = self.hub.now + self.timeout
        self.hub.arm(self, self.deadline)
        host, port = self.endpoint.host, self.endpoint.port
        try:
            ip = ipaddress.ip_address(host)
        except ValueError:  # a name: resolved on the hub's helper thread, never on this one
            self.hub.resolve(self, self.attempt_id)
            return
        self.dial([(socket.AF_INET6 if ip.version == 6 else socket.AF_INET, (host, port))])

    def dial(self, addresses: list[Address]) -> None:
        """Connect to the first of the addresses; a refusal tries the next, as asyncio does."""
        family, sockaddr = addresses[0]
        self.addresses = addresses[1:]
        sock = socket.socket(family, socket.SOCK_STREAM)
        sock.setblocking(False)
        sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        err = sock.connect_ex(sockaddr)
        if err not in CONNECTING:
            sock.close()
            self.cannot_connect(f"[Errno {err}] {os.strerror(err)}")
            return
        self.sock = sock
        self.hub.selector.register(sock, WRITE, self)  # writable once connected (or refused)

    def resolved(self, attempt_id: int, addresses: list[Address], error: str) -> None:
        if attempt_id != self.attempt_id or not self.connecting or self.sock is not None:
            return  # an attempt that has timed out already
        if addresses:
            self.dial(addresses)
        else:
            self.cannot_connect(error)

    def cannot_connect(self, why: str) -> None:
        if self.addresses:  # refused at one address: the next one
            self.close_socket()
            self.dial(self.addresses)
            return
        self.retry(LinkError(f"cannot connect to {self.endpoint}: {why}"))

    def close(self) -> None:
        self.close_socket()
        self.connecting = False
        self.attempt_id += 1
        self.addresses = []
        self.buf = self.rest = b""
        self.frame = None
        self.deadline = 0.0

    def close_socket(self) -> None:
        sock, self.sock = self.sock, None
        if sock is not None:
            self.hub.selector.unregister(sock)
            sock.close()

    def ready(self, events: int) -> None:
        """The selector's events for this node's socket."""
        sock = self.sock
        assert sock is not None
        if self.connecting:
            err = sock.getsockopt(socket.SOL_SOCKET, socket.SO_ERROR)
            if err:
                self.cannot_connect(f"[Errno {err}] {os.strerror(err)}")
                return
            self.connecting = False
            self.hub.selector.modify(sock, READ, self)
            if self.frame is not None:
                self.transmit()
            return
        if events & WRITE and self.rest:
            try:
                sent = sock.send(self.rest)
            except BlockingIOError:
                sent = 0
            except OSError as e:
                self.retry(LinkError(f"{self.frame.what if self.frame else 'send'}: connection lost: {e}"))
                return
            self.rest = self.rest[sent:]
            if not self.rest:
                self.hub.selector.modify(sock, READ, self)
        if events & READ:
            self.receive(sock)

    def receive(self, sock: socket.socket) -> None:
        try:
            data = sock.recv(65536)
        except BlockingIOError:
            return
        except OSError as e:
            self.lost(f"connection lost: {e}")
            return
        if not data:
            self.lost("connection lost")
            return
        buf = self.buf + data if self.buf else data
        at, end = 0, len(buf)
        while at < end:
            try:
                size = frame_size(buf, at)
            except FrameError as e:
                self.lost(str(e))
                return
            if not size:
                break
            frame = self.frame
            if frame is not None and buf[at] << 8 | buf[at + 1] == self.tid:  # else a late answer: dropped
                try:
                    answer = answer_data(frame, buf, at, size)
                except DeviceError as e:  # an answer, and the connection is sound: not retried
                    self.end(None, self.failed(e, self.where, self.key))
                except FrameError as e:
                    self.retry(e)
                    return
                else:
                    self.frame = None
                    self.advance(answer)
                if self.sock is not sock:
                    return
            at += size
        self.buf = buf[at:]

    def lost(self, why: str) -> None:
        """The connection failed or carried what is not Modbus TCP: an attempt failed if one was
        in flight; an idle connection is just made again for the next request."""
        if self.frame is not None:
            self.retry(LinkError(f"{self.frame.what}: {why}"))
        else:
            self.close()

    def tick(self, now: float) -> None:
        """The node's timer: a timeout of what is in flight, or the idle probe."""
        if self.deadline:
            if now + 1e-3 < self.deadline:  # the timer was set for an earlier transaction
                self.hub.arm(self, self.deadline)
            elif self.connecting:
                self.retry(LinkError(f"cannot connect to {self.endpoint}: timed out"))
            else:
                what = self.frame.what if self.frame is not None else "request"
                self.retry(LinkError(f"{what}: no answer within {self.timeout:g} s"))
        elif self.req is None and not self.queue:
            due = max(self.active + self.idle, self.retry_at)
            if now < due:
                self.hub.arm(self, due)
            else:
                self.active = now
                self.stats.probes += 1
                self.submit(self.probe)


class TcpHub:
    """The thread, its selector and timer heap, serving the exchange's Modbus TCP nodes."""

    def __init__(self) -> None:
        self.selector = selectors.DefaultSelector()
        self.nodes: dict[int, TcpNode] = {}
        self.outbox: deque[Request] = deque()  # engine thread -> this thread
        self.inbox: deque[Callable[[], None]] = deque()  # helper threads -> this thread
        self.timers: list[tuple[float, int, TcpNode]] = []  # (when, sequence number, node)
        self.now = time.monotonic()  # as of the last wake-up of the thread: a read asks no clock
        self._seq = itertools.count()
        self._woken = False  # a wake-up byte is on its way
        self._waiting = False  # the thread is in (or about to enter) select
        self._stopping = False
        self._wake_r, self._wake_w = socket.socketpair()
        self._wake_r.setblocking(False)
        self._wake_w.setblocking(False)
        self.selector.register(self._wake_r, READ, None)
        self._resolver: ThreadPoolExecutor | None = None
        self._thread = threading.Thread(target=self._run, name="netplc-exchange-tcp", daemon=True)

    def add(self, node: TcpNode) -> None:
        self.nodes[node.config.node] = node
        self.arm(node, node.active + node.idle)

    def start(self) -> None:
        self._thread.start()

    def stop(self, timeout: float = 5.0) -> None:
        """The thread may see `_stopping` and end before the wake-up is sent: the sending end is
        closed here, after the join, never by the thread."""
        self._stopping = True
        self._wake()
        if self._thread.is_alive():
            self._thread.join(timeout)
        self._wake_w.close()

    # --- from other threads ----------------------------------------------------------------------

    def submit(self, req: Request) -> None:
        """Engine thread: a request for one of the nodes. The thread is woken once per batch, and
        only while it waits: busy, it takes the outbox before it waits again."""
        self.outbox.append(req)
        if self._waiting and not self._woken:
            self._woken = True
            self._wake()

    def call(self, fn: Callable[[], None]) -> None:
        """Any thread: run `fn` on the thread (a name looked up); nothing once it has stopped."""
        if self._stopping:
            return
        self.inbox.append(fn)
        self._woken = True
        self._wake()

    def _wake(self) -> None:
        try:
            self._wake_w.send(b"\0")
        except BlockingIOError:  # the pipe is full of wake-ups already
            pass
        except OSError:
            if not self._stopping:
                raise
            # stopped meanwhile (a name looked up as the hub stops): nobody left to wake

    # --- on the thread ---------------------------------------------------------------------------

    def arm(self, node: TcpNode, when: float) -> None:
        if when < node.timer:
            node.timer = when
            heapq.heappush(self.timers, (when, next(self._seq), node))

    def resolve(self, node: TcpNode, attempt_id: int) -> None:
        """Look the node's host name up on a helper thread (a slow name server must not stall the
        other nodes); the answer comes back through `call`."""
        if self._resolver is None:
            self._resolver = ThreadPoolExecutor(1, thread_name_prefix="netplc-exchange-dns")
        host, port = node.endpoint.host, node.endpoint.port
        future = self._resolver.submit(socket.getaddrinfo, host, port, type=socket.SOCK_STREAM)

        def done(f: Future[list[tuple]]) -> None:
            try:
                found: list[Address] = [(family, sockaddr[:2]) for family, _, _, _, sockaddr in f.result()]
                error = ""
            except OSError as e:
                found, error = [], str(e)
            self.call(lambda: node.resolved(attempt_id, found, error))

        future.add_done_callback(done)

    def _run(self) -> None:
        try:
            while not self._stopping:
                timers = self.timers
                timeout = max(0.0, timers[0][0] - time.monotonic()) if timers else None
                self._waiting = True  # first, then look: a request queued after the look wakes us
                if self.outbox or self.inbox:
                    timeout = 0.0
                ready = self.selector.select(timeout)
                self._waiting = False
                self.now = time.monotonic()
                for key, events in ready:
                    node = key.data
                    if node is None:
                        self._woke()
                    elif node.sock is key.fileobj:  # else closed and perhaps made again meanwhile
                        try:
                            if events == READ and not node.connecting:
                                node.receive(key.fileobj)
                            else:
                                node.ready(events)
                        except Exception as e:  # a bug must not end the thread, nor show the link up
                            logger.exception(CRASHED, node.config.node)
                            node.crashed(e)
                if self.outbox or self.inbox:
                    self._drain()
                now = self.now
                while timers and timers[0][0] <= now:
                    when, _, node = heapq.heappop(timers)
                    if when == node.timer:  # else superseded by an earlier one
                        node.timer = math.inf
                        try:
                            node.tick(now)
                        except Exception as e:
                            logger.exception(CRASHED, node.config.node)
                            node.crashed(e)
        finally:
            for node in self.nodes.values():
                node.close()
            self.selector.close()
            self._wake_r.close()
            if self._resolver is not None:
                self._resolver.shutdown(wait=False, cancel_futures=True)

    def _woke(self) -> None:
        with contextlib.suppress(BlockingIOError):
            self._wake_r.recv(4096)  # what is left wakes the selector once more: harmless
        self._woken = False  # a request queued from now on wakes the thread again (if it waits)

    def _drain(self) -> None:
        inbox, outbox, nodes = self.inbox, self.outbox, self.nodes
        while inbox:
            fn = inbox.popleft()
            fn()
        while outbox:
            req = outbox.popleft()
            node = nodes[req.node]
            try:
                node.queue.append(req)
                if node.req is None:
                    node.next()
            except Exception as e:  # a bug must not end the thread, nor show the link up
                logger.exception(CRASHED, node.config.node)
                node.crashed(e)
