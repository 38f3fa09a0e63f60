"""NetPlc's records, by name, in English: the exchange's links, the operator's writes and forces,
the engine's own faults. netplc imports nothing of app, so its host says them: the engine and the
exchange each hold a `Say` (`words`), English (`english`) until the station sets its catalogue in
its `Language` (app/scada/words.py, which holds these texts and their Russian); a record is said
once, when it happens, never translated after."""

from __future__ import annotations

from collections.abc import Callable

WORDS = {
    # the exchange (netplc/exchange.py)
    "link up": "node {node} ({endpoint}): link up",
    "link down": "node {node} ({endpoint}): link down",
    "link down because": "node {node} ({endpoint}): link down: {error}",
    # the operator's writes (netplc/engine.py): the address as the documents print it, or a label
    "write": "write {where}: {old} -> {new}",
    "write change": "write {where}: {change} (raw {old} -> {new} at {addr})",
    "bits": "{addr}:{n} bits",
    "not io bits": "bits {addr}+{n} are not I/O bits",
    "write refused": "write refused: {error}",
    "write failed": "queued write failed: {error}",
    # the engine's own (netplc/engine.py)
    "emergency stop by": "NetPlc stopped, code 11: emergency-stop bit 03770 written by {user}",
    "watchdog": "watchdog: the scan did not reach its end (endless jump loop)",
    "listener failed": "engine listener {name} failed (the others go on): {error}",
    "FON failed": "FON {name} at line {line}: {error}",
    # the Modbus server's own (netplc/modbus/)
    "peer refused": "Modbus server refused a connection from {peer}: {n} connections from {host} are open "
                    "(max_per_peer)",
    "server full": "Modbus server refused a connection from {peer}: {n} connections are open "
                   "(max_connections)",
    "not modbus tcp": "Modbus server closed the connection of {peer}: not Modbus TCP (protocol {proto}, "
                      "length {length})",
    "idle half": "Modbus server closed the connection of {peer}: half a frame received for {idle:g} s "
                 "(idle_timeout)",
    "idle nothing": "Modbus server closed the connection of {peer}: nothing received for {idle:g} s "
                    "(idle_timeout)",
    "accept failed": "Modbus server: accept() failed: {error}",
    "more like it": "{text} (and {n} more like it in the last minute)",
    "rtu cannot open": "Modbus RTU on {port} cannot be opened: {error}",
    "rtu failed": "Modbus RTU on {port} failed: {error}",
    "rtu retrying": "{fault}; retrying every {every:g} s",
    "rtu works": "Modbus RTU on {port} works again",
    # forces (netplc/forcing.py, app/scada/forcing.py)
    "force": "force {where}: {was} -> {value}{how}",
    "forced value": "forced {value}",
    "bumpless": " (bumpless)",
    "raw value": "{value} (raw {raw})",
    "unforce": "unforce {where} (was forced {value})",
    "unforce all": "unforce {where} (was forced {value}; unforce all)",
    "force kind": "force kind {kind!r} is not one of {kinds}",
    "cannot force": "cannot force {kind} {addr}: {error}",
    "does not fit": "{value} does not fit a {kind} (0..{most})",
    "force NaN": "cannot force {name} to NaN",
}
Say = Callable[..., str]  # `say(name, **values)`: a record's text


def english(name: str, /, **values: object) -> str:
    return WORDS[name].format(**values)
