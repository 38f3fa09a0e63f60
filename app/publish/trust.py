"""`python main.py opcua trust STATION THUMBPRINT_OR_FILE`: trust an OPC UA client's certificate.

The engineer at the station's PC moves a refused certificate (pki/rejected/, named by the
thumbprint the journal gave) or a certificate file the client's owner handed over into
pki/trusted/; the running server reads it at the client's next connection. Whoever may change the
station folder may do this (as with `main.py users`); the station's journal records it.
"""

from __future__ import annotations

import argparse
import getpass
import sqlite3
import sys

from app.publish.pki import TrustError, TrustList, subject, thumbprint
from app.station.config import ConfigError, load_station, station_file
from netplc.records import Record
from registrar.store import Store


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(prog="python main.py opcua",
                                description="The OPC UA server's trust list of client certificates "
                                            "(pki/trusted/ and pki/rejected/ in the station folder).")
    sub = p.add_subparsers(dest="action", required=True)
    trust = sub.add_parser("trust", help="trust a client certificate: move it from pki/rejected/ (by the "
                                         "thumbprint the journal names) or copy a certificate file into "
                                         "pki/trusted/")
    trust.add_argument("station", help="station folder or its station.toml")
    trust.add_argument("certificate", help="the certificate's SHA-1 thumbprint, or a certificate file "
                                           "(DER or PEM)")
    return p


def main(argv: list[str]) -> int:
    ns = _parser().parse_args(argv)
    try:
        station = load_station(station_file(ns.station))
        path, der = TrustList(station.folder).trust(ns.certificate)
    except (ConfigError, TrustError, OSError) as e:
        print(f"opcua trust: {e}", file=sys.stderr)
        return 1
    text = f"OPC UA client certificate trusted: {subject(der)} (thumbprint {thumbprint(der)}), {path}"
    store = Store(station.Archive)
    try:
        store.start()
        store.put(Record(store.wallclock(), "operator", source=f"{getpass.getuser()} (main.py opcua trust)",
                         text=text))
    except (OSError, sqlite3.Error) as e:  # trusted all the same; say that the journal does not know
        print(f"opcua trust: {station.Archive}: not journaled: {e}", file=sys.stderr)
    finally:
        store.close()
    print(text)
    return 0
