"""The OPC UA servers of a test run take the standard address space from one cache of the run
(app/publish/standard_nodes.py, in .pytest_cache: kept between runs), made by the first worker
that needs it while the others wait, and each process loads it before its first test that may
start a server (the conftest then freezes it out of the collector's way). The stations the tests
start as processes inherit the folder."""

from __future__ import annotations

import os
from pathlib import Path

from app.publish import standard_nodes

FOLDER = Path(__file__).resolve().parents[1] / ".pytest_cache" / "netplc"  # ignored by git
# from the import on (tests/app/publish/conftest.py imports this module at collection, which
# every worker makes of the whole suite): a station a test starts as a process before this
# process's first server takes the run's cache too, and none writes to the user's home
os.environ.setdefault(standard_nodes.CACHE_ENV, str(FOLDER))
_loaded = False


def fill_once() -> bool:
    """From now on, servers of this process and of the processes it starts take their standard
    address space from the run's cache (True: loaded now)."""
    global _loaded
    if _loaded:
        return False
    standard_nodes.kept()
    _loaded = True
    return True
