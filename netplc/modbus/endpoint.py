"""Where a node is: `tcp://host:port` or `rtu://device?baudrate=...`, parsed once, with an error
that shows the expected form."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any
from urllib.parse import parse_qsl, urlsplit

from serial import SerialBase

from netplc.words import Phrase, WordedError, phrase

PARITIES = ("N", "E", "O")
BAUDRATES: tuple[int, ...] = SerialBase.BAUDRATES  # the standard rates every platform's port takes
STOPBITS = (1, 2)
BYTESIZES = (5, 6, 7, 8)


@dataclass(frozen=True, slots=True)
class Endpoint:
    """`tcp://host:port` or `rtu:///dev/ttyX?baudrate=19200&parity=E&bytesize=8&stopbits=1`; the serial
    defaults are the Modbus serial line's (even parity; 2 stop bits with no parity), the same as the
    station's own RTU server, so that a node and a server left at their defaults talk."""

    scheme: str  # "tcp" | "rtu"
    host: str = ""
    port: int = 502
    device: str = ""
    baudrate: int = 19200
    parity: str = "E"
    bytesize: int = 8
    stopbits: int = 1

    def __str__(self) -> str:
        if self.scheme == "tcp":
            return f"tcp://{self.host}:{self.port}"
        return f"rtu://{self.device}?baudrate={self.baudrate}&parity={self.parity}"


def parse_endpoint(text: str) -> Endpoint:
    """Parse an endpoint; a ValueError (WordedError, netplc/words.py) says what is wrong with it
    and shows the expected form."""
    forms = phrase("ep forms")
    try:
        url = urlsplit(text.strip())
        port = url.port
    except ValueError as e:
        raise WordedError("ep wrong", text=text, error=e, forms=forms) from None
    if url.scheme == "tcp":
        if not url.hostname:
            raise WordedError("ep no host", text=text, forms=forms)
        if url.path not in ("", "/") or url.query:
            raise WordedError("ep tcp path", text=text, forms=forms)
        try:
            url.hostname.encode("idna")
        except UnicodeError:
            raise WordedError("ep bad host", text=text, host=url.hostname) from None
        return Endpoint("tcp", host=url.hostname, port=port if port is not None else 502)
    if url.scheme == "rtu":
        # rtu:///dev/ttyS0 names a device path; rtu://COM3 a Windows port (the URL's "host")
        device = url.path if not url.netloc else url.netloc if not url.path else ""
        if not device:
            raise WordedError("ep no device", text=text, forms=forms)
        options: dict[str, Any] = {}
        for key, value in parse_qsl(url.query, keep_blank_values=True):
            if key == "parity":
                if value.upper() not in PARITIES:
                    raise WordedError("ep parity", text=text, value=value)
                options[key] = value.upper()
            elif key in ("baudrate", "bytesize", "stopbits"):
                if not value.isdigit() or int(value) <= 0:
                    raise WordedError("ep not positive", text=text, key=key, value=value)
                options[key] = int(value)
            else:
                raise WordedError("ep option", text=text, key=key)
        if "parity" in options:  # else the defaults, even parity and 1 stop bit, keep the rule
            options.setdefault("stopbits", default_stopbits(options["parity"]))
        endpoint = Endpoint("rtu", device=device, **options)
        if problems := line_problems(endpoint):
            raise WordedError("ep line", text=text, problem=problems[0][1])
        return endpoint
    raise WordedError("ep scheme", text=text, scheme=url.scheme, forms=forms)


def default_stopbits(parity: str) -> int:
    """The Modbus serial line's rule, 11 bits a character: 1 stop bit after a parity bit, 2 without."""
    return 2 if parity == "N" else 1


def line_problems(endpoint: Endpoint) -> list[tuple[str, Phrase]]:
    """(setting, problem) for each serial line setting of an rtu endpoint that a port cannot take:
    a typo in a rate would otherwise open the port at a speed nobody on the line talks."""
    checks = (("baudrate", endpoint.baudrate, BAUDRATES), ("parity", endpoint.parity, PARITIES),
              ("stopbits", endpoint.stopbits, STOPBITS), ("bytesize", endpoint.bytesize, BYTESIZES))
    return [(key, phrase("line not one of", key=key, value=value, allowed=", ".join(map(str, allowed))))
            for key, value, allowed in checks if value not in allowed]
