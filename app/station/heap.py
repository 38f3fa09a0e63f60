"""What a station's start built, moved out of the cyclic garbage collector's walk.

A full collection walks every object the collector tracks, and in a running station most of them
were built by the start and live until the process ends: modules, the program, the engine, the
forms and their widgets and caches, the OPC UA address space. With a 300-element form that is about
50,000 objects and 350,000 references spread over 120 MB: 25-40 ms of whichever thread collects
(the GUI thread in a window, app/gui/application.py), the worst tick of the form at three times its
median (bench/hmi.py); with OPC UA's 400,000 objects a headless station's collection took 0.2-0.3 s.
gc.freeze() puts them in the permanent generation, which no collection walks; whatever is made
afterwards is collected as before, and what the start built is still freed by its reference counts
when it goes. What is lost: a reference cycle among those objects that dies before the process ends
stays in memory (a simulated node restarted from the demo's menu leaves its old one's cycles, a
remote console a form the station changed), so this is done once per process: after the start of
the station it runs, or once a remote console shows its station's forms.
"""

from __future__ import annotations

import gc

_settled = False


def settle() -> None:
    """Collect what the start left over, then freeze the rest; once per process (later calls do nothing)."""
    global _settled
    if _settled:
        return
    _settled = True
    gc.collect()
    gc.freeze()
