"""The saved trends file and what a trend says of a range, without Qt."""

from __future__ import annotations

import math
import re
from pathlib import Path

import numpy as np
import pytest

from app.scada.trends import Pen, SavedTrend, TrendBook, TrendFileError, csv_rows, stats, value_at


def test_trends_are_kept_per_user_and_a_broken_file_is_named(tmp_path: Path) -> None:
    book = TrendBook(tmp_path)
    assert book.names("operator") == []
    book.put("operator", SavedTrend("Печь", [Pen("TEMP", "#d62728")], 600.0))
    book.put("engineer", SavedTrend("Бак", [Pen("LEVEL", "#1f77b4")]))
    assert book.names("operator") == ["Печь"] and book.names("engineer") == ["Бак"]
    assert book.get("operator", "Печь") == SavedTrend("Печь", [Pen("TEMP", "#d62728")], 600.0)
    assert book.get("engineer", "Печь") is None
    book.path.write_text("{not json", encoding="utf-8")
    with pytest.raises(TrendFileError, match=re.escape(str(tmp_path / "trends.json"))):
        book.names("operator")


def test_cursor_values_hold_the_last_sample_and_statistics_skip_gaps() -> None:
    ts = np.array([10.0, 20.0, 30.0, 40.0])
    vs = np.array([1.0, 2.0, np.nan, 4.0])
    assert math.isnan(value_at(ts, vs, 5.0))
    assert value_at(ts, vs, 25.0) == 2.0 and value_at(ts, vs, 40.0) == 4.0
    s = stats(ts, vs, 10.0, 40.0)
    assert s is not None and (s.min, s.max, s.mean) == (1.0, 4.0, 7 / 3)
    assert stats(ts, vs, 41.0, 50.0) is None
    rows = csv_rows([("A", ts, vs), ("B", np.array([20.0, 25.0]), np.array([5.0, 6.0]))], 15.0, 30.0)
    assert [r[1:] for r in rows] == [["A", "B"], ["2", "5"], ["", "6"], ["", ""]]
