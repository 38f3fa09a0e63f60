"""Arbitrary text for the properties: every character UTF-8 encodes, as `st.text()` draws by default.

`st.text()`'s default alphabet is `st.characters(codec="utf-8")`, whose table hypothesis builds by
encoding each of the 1.1 million code points (4 s of CPU) and keeps under .hypothesis/, which a
clean copy of the repository lacks: each pytest worker built it again. UTF-8 encodes every code
point but the surrogates, so the same characters are those of every category but Cs, which
hypothesis reads from its table of categories (0.25 s to build)."""

from __future__ import annotations

from hypothesis import strategies as st

CHARACTERS = st.characters(exclude_categories=["Cs"])


def any_text(max_size: int) -> st.SearchStrategy[str]:
    """`st.text(max_size=max_size)`: the same strings, without the codec's table."""
    return st.text(CHARACTERS, max_size=max_size)
