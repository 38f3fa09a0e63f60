"""Arranging elements: alignment, equal spacing and z-order, worked out on plain boxes and lists so
the rules can be read (and tested) apart from the canvas."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, TypeVar

T = TypeVar("T")
Box = tuple[int, int, int, int]  # x, y, w, h
Z_ORDERS = {"front": "Bring to front", "back": "Send to back", "raise": "Raise", "lower": "Lower"}


def number(value: Any, default: int) -> int:
    """An integer property as the file has it, or `default` while it is missing or not an integer."""
    return value if isinstance(value, int) and not isinstance(value, bool) else default


def box(raw: dict[str, Any]) -> Box:
    return number(raw.get("x"), 0), number(raw.get("y"), 0), number(raw.get("w"), 1), number(raw.get("h"), 1)


def aligned(boxes: list[Box], how: str) -> list[Box]:
    """The boxes on the outermost edge of them all (left, right, top, bottom) or on their middle
    (hcenter, vcenter); never left of or above the form's corner."""
    left = min(b[0] for b in boxes)
    top = min(b[1] for b in boxes)
    right = max(b[0] + b[2] for b in boxes)
    bottom = max(b[1] + b[3] for b in boxes)
    out = []
    for x, y, w, h in boxes:
        if how == "left":
            x = left
        elif how == "right":
            x = right - w
        elif how == "top":
            y = top
        elif how == "bottom":
            y = bottom - h
        elif how == "hcenter":
            x = round((left + right) / 2 - w / 2)
        elif how == "vcenter":
            y = round((top + bottom) / 2 - h / 2)
        out.append((max(0, x), max(0, y), w, h))
    return out


def distributed(boxes: list[Box], axis: str) -> list[Box]:
    """Equal gaps between the boxes along x ("h") or y ("v"), the first and the last staying where
    they are; the result is in the order given."""
    i = 0 if axis == "h" else 1
    order = sorted(range(len(boxes)), key=lambda k: boxes[k][i])
    first, last = boxes[order[0]], boxes[order[-1]]
    gap = (last[i] + last[2 + i] - first[i] - sum(b[2 + i] for b in boxes)) / (len(boxes) - 1)
    out = list(boxes)
    pos = float(first[i])
    for k in order:
        moved = list(boxes[k])
        moved[i] = round(pos)
        out[k] = (moved[0], moved[1], moved[2], moved[3])
        pos += boxes[k][2 + i] + gap
    return out


def restacked(order: list[T], picked: Callable[[T], bool], how: str) -> list[T]:
    """The z-order (bottom first) with the picked items brought to the front, sent to the back, or
    raised or lowered past one other item, keeping their order among themselves."""
    chosen = [x for x in order if picked(x)]
    rest = [x for x in order if not picked(x)]
    if how == "front":
        return rest + chosen
    if how == "back":
        return chosen + rest
    out = list(order)
    step = 1 if how == "raise" else -1
    for j in range(len(out) - 2, -1, -1) if step == 1 else range(1, len(out)):
        if picked(out[j]) and not picked(out[j + step]):
            out[j], out[j + step] = out[j + step], out[j]
    return out
