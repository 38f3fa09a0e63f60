"""Where each published point goes in Sparkplug: the edge node's own metrics, or a device.

Each node of the exchange (a PLC the station reads with NREAD) is a Sparkplug device of the
station's edge node, named by its station.toml `name` (or Node<n>): its metrics are its link
(`Link/Up`, `Link/Errors`, `Link/LastError`, `Link/Endpoint`) and the points its NREADs fill, so a
host sees the PLC die (DDEATH) and come back (DBIRTH) with the data it gave. Which NREADs fill a
point is the quality map's knowledge (app/scada/quality.py); a point that no NREAD fills (what
the program computes, setpoints it sends with NWRITE) or that several nodes fill is the edge
node's own.

Aliases are unique across the edge node and its devices (spec 3.0, 6.4.6): point i is alias i + 1
wherever it is published, and each device's link metrics come after the points.
"""

from __future__ import annotations

from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np

from app.publish.sparkplug import BOOLEAN, STRING, UINT64
from app.scada.quality import QualityMap
from app.scada.tag import Tag
from netplc.exchange import NodeConfig, NodeStats

LINK = (("Link/Up", BOOLEAN), ("Link/Errors", UINT64), ("Link/LastError", STRING), ("Link/Endpoint", STRING))
LINK_NAMES = frozenset(name for name, _ in LINK)


@dataclass(frozen=True)
class Device:
    """One exchange node as a Sparkplug device."""

    index: int  # in Layout.devices
    node: int  # the node number (NODE S:n)
    id: str  # the Sparkplug device id: the node's name, or Node<n>
    points: np.ndarray  # the indexes of the points it publishes
    first_alias: int  # of its link metrics, in the order of LINK

    @staticmethod
    def link(stats: NodeStats | None) -> tuple[bool, int, str, str]:
        """The values of its link metrics (up while it lives: a dead device has no values)."""
        if stats is None:
            return True, 0, "", ""
        return True, stats.errors, stats.last_error, stats.endpoint


class Layout:
    """The points of the edge node and of each device, worked out once when the publisher starts."""

    def __init__(self, tags: Sequence[Tag], quality_map: QualityMap | None,
                 nodes: Iterable[NodeConfig]) -> None:
        configs = sorted(nodes, key=lambda c: c.node)
        number = {cfg.node: k for k, cfg in enumerate(configs)}
        owner = np.full(len(tags), -1, dtype=np.intp)  # point -> device index, -1: the edge node's
        if quality_map is not None:
            for i, tag in enumerate(tags):
                fed = {f.node for f in quality_map.feeding(*tag.footprint())}
                if len(fed) == 1 and (node := fed.pop()) in number:
                    owner[i] = number[node]
        self.owner = owner
        self.node_points = np.flatnonzero(owner < 0)
        self.devices = [Device(k, cfg.node, cfg.title, np.flatnonzero(owner == k),
                               len(tags) + 1 + k * len(LINK)) for k, cfg in enumerate(configs)]
        self.by_id = {d.id: d for d in self.devices}
        self.index = {t.name: i for i, t in enumerate(tags)}

    def point(self, device: Device | None, name: str, alias: int) -> int | None:
        """The point a command's metric names, by name or else by alias, if it is one of the edge
        node's (`device` None) or of that device; None otherwise."""
        i = self.index.get(name) if name else alias - 1
        if i is None or not 0 <= i < len(self.owner):
            return None
        return i if self.owner[i] == (-1 if device is None else device.index) else None

    def link_name(self, device: Device, name: str, alias: int) -> str:
        """The link metric a command's metric names ("" if none)."""
        if name:
            return name if name in LINK_NAMES else ""
        k = alias - device.first_alias
        return LINK[k][0] if 0 <= k < len(LINK) else ""
