"""NetPlc network functions NODE (300), NREAD (301), NWRITE (302): spec section 4.3,
docs/architecture.md sections 1 and 6.

They only hand block requests to the exchange (netplc/exchange.py) and never wait for the network;
the data read arrives in memory at the start of a later scan. Output C+1 is the node's link state
(1 = link up), the manual's "0 when the PLC is off, 1 when on". Without an exchange (`python -m
netplc run`, tests of other functions) there is no link, so C+1 = 0.
"""

from __future__ import annotations

from netplc.functions._util import Step, built
from netplc.functions.registry import Fon, FonContext, register
from netplc.memory import Memory


@register(300, "NODE", s="D", limits=(("S", 0, 255),))
@built
def node(mem: Memory, fon: Fon) -> Step:
    """Select the node of the following NREAD/NWRITE (kept until the next NODE, across scans).
    Nodes are numbered 0...255 (the manual's range): another number is a load error."""
    number = fon.s or 0

    def step(ctx: FonContext) -> None:
        ctx.node = number

    return step


@register(301, "NREAD", s="O", d="M", r="D")
@built
def nread(mem: Memory, fon: Fon) -> Step:
    """Read R bytes at the node's address S into local D."""
    # built once: at a fast tick every NREAD runs every scan, most finding their request in flight
    key, remote, local, length = fon.index, fon.s or 0, fon.d or 0, fon.r or 0
    link, bits = fon.c + 1, mem.bits

    def step(ctx: FonContext) -> None:
        ex = ctx.exchange
        bits[link] = 1 if ex is not None and ex.request_read(key, ctx.node, remote, local, length) else 0

    return step


@register(302, "NWRITE", s="M", d="O", r="D")
def nwrite(ctx: FonContext, fon: Fon) -> None:
    """Write R bytes of local S to the node's address D (the bytes as they are in this scan)."""
    ex = ctx.exchange
    up = False
    if ex is not None:
        up = ex.request_write(fon.index, ctx.node, fon.d or 0, ctx.mem.read(fon.s or 0, fon.r or 0))
    ctx.mem.bits[fon.c + 1] = 1 if up else 0
