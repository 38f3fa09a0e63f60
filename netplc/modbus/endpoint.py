"""Where a node is: `tcp://host:port` or `rtu://device?baudrate=...`, parsed once, with an error
that shows the expected form."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any
from urllib.parse import parse_qsl, urlsplit

from serial import SerialBase

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
    """Parse an endpoint; ValueError says what is wrong with it and shows the expected form."""
    forms = "expected tcp://host:port, rtu:///dev/ttyX?baudrate=19200&parity=E or rtu://COM3?baudrate=..."
    try:
        url = urlsplit(text.strip())
        port = url.port
    except ValueError as e:
        raise ValueError(f"endpoint {text!r}: {e} ({forms})") from None
    if url.scheme == "tcp":
        if not url.hostname:
            raise ValueError(f"endpoint {text!r}: no host ({forms})")
        if url.path not in ("", "/") or url.query:
            raise ValueError(f"endpoint {text!r}: a tcp endpoint has no path or options ({forms})")
        try:
            url.hostname.encode("idna")
        except UnicodeError:
            raise ValueError(f"endpoint {text!r}: {url.hostname!r} is not a valid host name") from None
        return Endpoint("tcp", host=url.hostname, port=port if port is not None else 502)
    if url.scheme == "rtu":
        # rtu:///dev/ttyS0 names a device path; rtu://COM3 a Windows port (the URL's "host")
        device = url.path if not url.netloc else url.netloc if not url.path else ""
        if not device:
            raise ValueError(f"endpoint {text!r}: the serial device must follow rtu:// ({forms})")
        options: dict[str, Any] = {}
        for key, value in parse_qsl(url.query, keep_blank_values=True):
            if key == "parity":
                if value.upper() not in PARITIES:
                    raise ValueError(f"endpoint {text!r}: parity {value!r} is not N, E or O")
                options[key] = value.upper()
            elif key in ("baudrate", "bytesize", "stopbits"):
                if not value.isdigit() or int(value) <= 0:
                    raise ValueError(f"endpoint {text!r}: {key} {value!r} is not a positive number")
                options[key] = int(value)
            else:
                raise ValueError(f"endpoint {text!r}: unknown option {key!r} "
                                 "(baudrate, parity, bytesize, stopbits)")
        if "parity" in options:  # else the defaults, even parity and 1 stop bit, keep the rule
            options.setdefault("stopbits", default_stopbits(options["parity"]))
        endpoint = Endpoint("rtu", device=device, **options)
        if problems := line_problems(endpoint):
            raise ValueError(f"endpoint {text!r}: {problems[0][1]}")
        return endpoint
    raise ValueError(f"endpoint {text!r}: unknown scheme {url.scheme!r} ({forms})")


def default_stopbits(parity: str) -> int:
    """The Modbus serial line's rule, 11 bits a character: 1 stop bit after a parity bit, 2 without."""
    return 2 if parity == "N" else 1


def line_problems(endpoint: Endpoint) -> list[tuple[str, str]]:
    """(setting, problem) for each serial line setting of an rtu endpoint that a port cannot take:
    a typo in a rate would otherwise open the port at a speed nobody on the line talks."""
    checks = (("baudrate", endpoint.baudrate, BAUDRATES), ("parity", endpoint.parity, PARITIES),
              ("stopbits", endpoint.stopbits, STOPBITS), ("bytesize", endpoint.bytesize, BYTESIZES))
    return [(key, f"{key} {value!r} is not one of {', '.join(map(str, allowed))}")
            for key, value, allowed in checks if value not in allowed]
