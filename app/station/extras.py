"""The optional parts of NetPlc Station and the pip extras that install them (pyproject.toml):
OPC UA (`[opcua]`), MQTT Sparkplug B (`[mqtt]`), the plant archive on PostgreSQL (`[postgres]`).

A station whose configuration asks for a part that is not installed gets a problem naming the
extra and the command that installs it, at `check` and at start (`app/station/load.py`), and so do
the commands that need one; never an ImportError from deep inside a start. The libraries are
looked for, not imported (`importlib.util.find_spec`): their imports stay where they are used,
and only for a station that uses them.
"""

from __future__ import annotations

import importlib.util

from app.station.config import Station

PACKAGE = "netplc-station"
EXTRAS: dict[str, tuple[str, ...]] = {  # the modules each extra installs that the code imports
    "opcua": ("asyncua", "cryptography"),
    "mqtt": ("paho.mqtt", "google.protobuf"),
    "postgres": ("psycopg",),
}


def missing(extra: str) -> str | None:
    """The first module of `extra` that is not installed, or None when all are."""
    for module in EXTRAS[extra]:
        try:
            if importlib.util.find_spec(module) is None:
                return module
        except (ImportError, ValueError):  # no log: its parent package is missing, said by the return
            return module
    return None


def needs(extra: str, what: str) -> str | None:
    """`what` needs the extra: the words and the command, or None when it is installed."""
    module = missing(extra)
    if module is None:
        return None
    return f"{what} needs the extra: pip install '{PACKAGE}[{extra}]' ({module} is not installed)"


def station_problems(station: Station) -> list[str]:
    """Each part the station's configuration asks for whose extra is not installed."""
    wanted = (("opcua", "[opcua]", station.opcua.enabled), ("mqtt", "[mqtt]", station.mqtt.enabled),
              ("postgres", "Archive = postgresql://... (the plant archive)",
               station.plant_archive is not None))
    return [f"{station.path}: {problem}" for extra, what, used in wanted
            if used and (problem := needs(extra, what))]
