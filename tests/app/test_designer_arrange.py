"""The designer's arranging rules on plain boxes: align, distribute, z-order."""

from __future__ import annotations

from app.gui.designer.arrange import aligned, box, distributed, restacked


def test_align_on_the_outermost_edge_or_the_middle() -> None:
    boxes = [(10, 5, 20, 10), (40, 30, 10, 40)]
    assert aligned(boxes, "left") == [(10, 5, 20, 10), (10, 30, 10, 40)]
    assert aligned(boxes, "right") == [(30, 5, 20, 10), (40, 30, 10, 40)]
    assert aligned(boxes, "bottom") == [(10, 60, 20, 10), (40, 30, 10, 40)]
    assert aligned(boxes, "hcenter") == [(20, 5, 20, 10), (25, 30, 10, 40)]
    assert aligned(boxes, "vcenter") == [(10, 32, 20, 10), (40, 18, 10, 40)]  # 32.5, 17.5 rounded to even


def test_distribute_keeps_the_outer_two_and_evens_the_gaps() -> None:
    boxes = [(100, 0, 10, 10), (0, 0, 10, 10), (12, 50, 30, 10)]
    out = distributed(boxes, "h")
    assert out[1] == (0, 0, 10, 10) and out[0] == (100, 0, 10, 10)
    assert out[2][0] == 40  # gaps of 30 each side: 10..40 and 70..100
    assert distributed([(0, 0, 5, 5), (0, 6, 5, 5), (0, 100, 5, 5)], "v")[1] == (0, 50, 5, 5)


def test_z_order_moves_the_picked_items_together() -> None:
    order = list("abcde")
    picked = {"b", "c"}.__contains__
    assert restacked(order, picked, "front") == list("adebc")
    assert restacked(order, picked, "back") == list("bcade")
    assert restacked(order, picked, "raise") == list("adbce")
    assert restacked(order, picked, "lower") == list("bcade")
    assert restacked(order, {"e"}.__contains__, "raise") == order


def test_a_box_takes_defaults_for_what_the_file_lacks() -> None:
    assert box({"x": 3, "y": True, "w": "9"}) == (3, 0, 1, 1)
