"""NetPlc's records, by name, in English: the exchange's links, the operator's writes and forces,
the engine's own faults. netplc imports nothing of app, so its host says them: the engine and the
exchange each hold a `Say` (`words`), English (`english`) until the station sets its catalogue in
its `Language` (app/scada/words.py, which holds these texts and their Russian); a record is said
once, when it happens, never translated after. A problem a reader finds (an address, a program's
line, a symbol) is a `Phrase` too, or a `WordedError` carrying one: English as `str()` (the log,
a tool without a station), said in the station's language by whoever reports it with a station."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field

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
    # addresses (netplc/address.py, memory.py, functions/_util.py): as the documents print them
    "addr not octal": "{text!r} is not an octal number",
    "addr not data": "{addr} is not a data memory address",
    "addr past io": "{addr}: {n}-byte operand runs past bit 03777",
    "addr not valid": "{addr} is not a valid address",
    "addr past bank": "{addr}: {n}-byte operand runs past the end of its bank",
    "addr not int": "not an address (an integer from 0)",
    "addr not bit": "{addr} is neither an I/O bit nor a data bit (byte*8+bit)",
    "addr not io bit": "{addr} is not an I/O bit",
    "addr not hmi bit": "{addr} is not an HMI bit address",
    "addr bit past": "bit {k} of {addr} runs past bit 03777",
    "addr not bytes": "{first}..{last} is not a whole number of bytes",
    "addr mixes": "{first}..{last} mixes I/O bits and data memory",
    "addr missing": "missing operand",
    "addr no memory": "{addr} names no memory: neither an I/O bit (00000-03777), a data byte "
                      "(k*010000 + 04000-07777) nor a data bit (byte*8 + bit)",
    "addr too long": "an address of {n} characters names no memory",
    # symbols.csv and a program's lines (netplc/program.py): symbols, labels, mnemonics as they are
    "sym no address": "symbol {name!r} has no address",
    "sym bad name": "{name!r} is not a valid symbol name",
    "sym twice": "symbol {name!r} defined twice",
    "stl too big": "program needs {words} words; program memory holds {most}",
    "stl symbol not octal": "symbol {name!r}: {value!r} is not a $octal address",
    "stl label twice": "label {label!r} defined twice",
    "stl expected": "expected an instruction",
    "stl unknown": "unknown instruction {op!r}{hint}",
    "stl label hint": " (a label needs a colon: '{name}:')",
    "stl cannot read": "cannot read parameter at {text!r}",
    "stl no value": "{key}: has no value",
    "stl no more": "{op} takes no more parameters (extra {token!r})",
    "stl no such param": "{op} has no parameter {key}:",
    "stl takes none": "{op} takes no parameters",
    "stl given twice": "parameter {key}: given twice",
    "stl not octal address": "{key}: {token!r} is not an octal address",
    "stl offset long": "{key}: bit offset of {name!r} is over {n} digits",
    "stl unknown symbol": "{key}: unknown symbol {token!r}",
    "stl operand": "{key}: {error}",
    "stl needs c": "{op} needs C: (a bit address)",
    "stl not io bit": "C: {addr} is not an I/O bit (00000-03777)",
    "stl coil past": "C: {op} uses bits {first}-{last}, past I/O bit 03777",
    "stl const not address": "{key}: a constant is needed here, not the address {token!r}",
    "stl not bcd": "{key}: {token!r} is not a BCD constant (up to 4 decimal digits)",
    "stl not octal const": "{key}: {token!r} is not an octal number",
    "stl not decimal": "{key}: {token!r} is not a decimal number",
    "stl outside": "{key}: {token} is outside {bounds}",
    "stl needs label": "{op} needs a label",
    "stl not program address": "L: {token!r} is not an octal program address",
    "stl not start": "L: program address {token} is not the start of an instruction",
    "stl undefined label": "L: undefined label {token!r}",
    "stl needs preset": "{op} needs N: (preset 0-255)",
    "stl fon needs n": "FON needs N: (function number or mnemonic)",
    "stl not function number": "N: {token!r} is not a function number",
    "stl no function": "N: function {number} does not exist",
    "stl unknown function": "N: unknown function {token!r}",
    "stl fon no more": "FON {name} takes no more parameters (extra {token!r})",
    "stl takes no key": "{name} takes no {key}: parameter",
    "stl needs key": "{name} needs {key}: ({kind})",
    "stl kind M": "an address", "stl kind O": "an octal constant", "stl kind D": "a decimal constant",
    "stl kind B": "a BCD constant",
    # the program's network instructions against the nodes (netplc/exchange.py check_program_nodes)
    "stl node not configured": "NODE S:{node}: node {node} is not configured (configured nodes: {have})",
    "stl no nodes": "none",
    "stl local block": "{name}: local block of {length} bytes: {error}",
    "stl no node": "{name} with no NODE in the program talks to node 0, which is not configured (configured "
                   "nodes: {have})",
    "stl node map": "{name}: node {node}: {error}",
    "stl read only": "NWRITE: node {node}: table {table} is read-only",
    "map no bytes": "block length {length}: at least 1 byte is needed",
    "map remote": "remote {error}",
    "map table": "table {table!r} is not one of {tables}",
    "map past": "{table} {remote}+{count} runs past Modbus address 65535",
    "map profile": "profile {profile!r} is not one of {profiles}",
    # a node's settings (netplc/exchange.py node_problems, netplc/modbus/endpoint.py): values as they are
    "ep forms": "expected tcp://host:port, rtu:///dev/ttyX?baudrate=19200&parity=E or rtu://COM3?baudrate=...",
    "ep wrong": "endpoint {text!r}: {error} ({forms})",
    "ep no host": "endpoint {text!r}: no host ({forms})",
    "ep tcp path": "endpoint {text!r}: a tcp endpoint has no path or options ({forms})",
    "ep bad host": "endpoint {text!r}: {host!r} is not a valid host name",
    "ep no device": "endpoint {text!r}: the serial device must follow rtu:// ({forms})",
    "ep parity": "endpoint {text!r}: parity {value!r} is not N, E or O",
    "ep not positive": "endpoint {text!r}: {key} {value!r} is not a positive number",
    "ep option": "endpoint {text!r}: unknown option {key!r} (baudrate, parity, bytesize, stopbits)",
    "ep line": "endpoint {text!r}: {problem}",
    "ep scheme": "endpoint {text!r}: unknown scheme {scheme!r} ({forms})",
    "line not one of": "{key} {value!r} is not one of {allowed}",
    "node outside": "{node} is outside {lo}-{hi}",
    "node unit": "unit {unit} is not {lo}-{hi} on {scheme}{why}",
    "node unit why": " (0 is broadcast, which never answers; 248-255 are reserved)",
    "node not one of": "{value!r} is not one of {names}",
    "node count outside": "{value} is outside {least:g}-{most:g}",
    "node seconds outside": "{value:g} s is outside {least:g}-{most:g} s",
    "node name": "{name!r} may not hold '/', '+', '#', control characters or outer spaces (it names the "
                 "node in topics and paths)",
    "node backoff": "{backoff:g} s is more than backoff_max {most:g} s",
    "node twice": "node {node} is configured twice",
    "node title used": "{title!r} already names node {node}",
    # a station's text file that cannot be read (netplc/textfile.py): what the system says as it is
    "read file": "the file", "read program": "program", "read symbols": "symbols", "read tags": "the tags",
    "read messages": "the message catalog", "read users": "the users file",
    "read station": "the station file",
    "read form": "the form",
    "file cannot read": "cannot read {what}: {error}",
    "file not a file": "cannot read {what}: it is {kind}, not a file",
    "file too large": "cannot read {what}: larger than {mb} MB, the most a station file may hold",
    "file not text": "neither UTF-8 nor {fallback} text (byte 0x{byte:02X})",
    "file link loop": "a loop of symbolic links",
    "file outside": "{real} is outside the station folder {root} (allow_outside = true permits it)",
    "kind file": "a file", "kind folder": "a folder", "kind fifo": "a FIFO (named pipe)",
    "kind char": "a character device", "kind block": "a block device", "kind socket": "a socket",
    "kind special": "a special file",
    "csv field long": "a field is longer than {n} characters",
    "csv error": "{error}",
    "csv runs on": "a quoted field runs on to line {line}: a row is one line (a closing quote missing?)",
    "node shared line": "{endpoint} and node {node}'s {first} share {device} with different line settings",
}
Say = Callable[..., str]  # `say(name, **values)`: a record's text



@dataclass(frozen=True)
class Phrase:
    """A text of the catalogue by name with its values, said in a language when it is said."""

    name: str
    values: Mapping[str, object] = field(default_factory=dict)


def phrase(name: str, /, **values: object) -> Phrase:
    return Phrase(name, values)


class WordedError(ValueError):
    """An error whose text is a `Phrase`: English as `str()` (`in_english`, this catalogue's; a
    subclass of app names its own), said in a station's language by a host that reports it."""

    in_english: Say

    def __init__(self, name: str, /, **values: object) -> None:
        self.phrase = Phrase(name, values)
        super().__init__(name)

    def __str__(self) -> str:
        return str(said(type(self).in_english, self.phrase))


def said(say: Say, value: object) -> object:
    """A value as it goes into a sentence of `say`: a phrase or a worded error said, the rest as it is."""
    if isinstance(value, WordedError):
        value = value.phrase
    return say(value.name, **value.values) if isinstance(value, Phrase) else value


def speaker(table: Mapping[str, str]) -> Say:
    """The English `Say` of a catalogue (this one; registrar/words.py's)."""
    def say(name: str, /, **values: object) -> str:
        return table[name].format(**{k: said(say, v) for k, v in values.items()})
    return say


english = speaker(WORDS)


WordedError.in_english = english
