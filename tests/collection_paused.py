"""Python's cyclic collection paused while a test makes a great many objects that live to its end.

Each collection of the oldest generation walks every object still alive, and a test that builds
hundreds of thousands of them (the standard OPC UA address space twice, hypothesis's records of
hundreds of examples) crosses the thresholds again and again as its heap grows: a third of such a
test's CPU went to walks that found nothing to free. The test's garbage is collected once, at its
end."""

from __future__ import annotations

import gc
from collections.abc import Iterator

import pytest


@pytest.fixture
def collection_paused() -> Iterator[None]:
    """No automatic collection during the test; one collection after it."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()
        gc.collect()
