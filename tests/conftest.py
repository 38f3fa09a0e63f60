"""Headless Qt for the whole suite: without this, Qt aborts the process when there is no display."""

import os

os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")
