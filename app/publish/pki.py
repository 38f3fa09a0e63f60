"""The OPC UA server's own certificate and key, and the trust list of client certificates.

In the station folder, laid out as OPC UA stacks lay out a certificate store:

    pki/own/cert.der, pki/own/key.pem   the station's certificate and private key
    pki/trusted/                        client certificates the station trusts
    pki/rejected/                       client certificates it refused, one copy of each

The key is readable by its owner only (0600, in a folder only the owner may enter); a key found
readable by others is made private at start and the journal says so. The certificate names the
host as clients reach it (its host name, its fully qualified name, the address the endpoint is
bound to and the `[opcua] certificate_names`), since clients check that the name they connect to
is in it; it is made again, with the same key, when those names change or it expires. A client
whose certificate is not in `trusted/` is refused (standard OPC UA practice: no trust on first
use); its certificate lands in `rejected/`, and `python main.py opcua trust STATION THUMBPRINT`
moves it to `trusted/`, which the running server reads at the next connection.
"""

from __future__ import annotations

import datetime as dt
import hashlib
import ipaddress
import logging
import os
import shutil
import socket
import stat
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path

from cryptography import x509
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import rsa
from cryptography.x509.oid import ExtendedKeyUsageOID, NameOID

logger = logging.getLogger(__name__)

PKI = "pki"
OLD_CERT, OLD_KEY = "opcua-cert.der", "opcua-key.pem"  # where stations before the pki folder kept them
YEARS = 5  # a new certificate's life
RENEW_BEFORE = dt.timedelta(days=30)  # made again this long before it expires
REJECTED_AT_MOST = 256  # certificates kept in rejected/ (a flood of new ones is not kept)
CERT_SUFFIXES = (".der", ".pem", ".crt", ".cer")


class TrustError(ValueError):
    """A trust command that cannot be done, in words for whoever typed it."""


def thumbprint(der: bytes) -> str:
    """The certificate's SHA-1 thumbprint in hex, as OPC UA tools show it."""
    return hashlib.sha1(der, usedforsecurity=False).hexdigest().upper()


def load_der(path: Path) -> bytes:
    """A certificate file, DER or PEM, as DER; ValueError if it holds none."""
    data = path.read_bytes()
    if data.lstrip().startswith(b"-----BEGIN"):
        return x509.load_pem_x509_certificate(data).public_bytes(serialization.Encoding.DER)
    x509.load_der_x509_certificate(data)
    return data


def subject(der: bytes) -> str:
    try:
        cert = x509.load_der_x509_certificate(der)
    except ValueError:
        return "?"
    names = cert.subject.get_attributes_for_oid(NameOID.COMMON_NAME)
    return str(names[0].value) if names else cert.subject.rfc4514_string()


def host_names(bound: str, extra: Iterable[str] = ()) -> list[str]:
    """The names and addresses a client may reach this host by: its host name, its fully
    qualified name, the bound address (unless it is every address) and `extra`."""
    names = [socket.gethostname(), socket.getfqdn()]
    if bound and bound not in ("0.0.0.0", "::"):
        names.append(bound)
    names += list(extra)
    return list(dict.fromkeys(n for n in names if n))


def _general_names(uri: str, names: Iterable[str]) -> list[x509.GeneralName]:
    out: list[x509.GeneralName] = [x509.UniformResourceIdentifier(uri)]
    for name in names:
        try:
            out.append(x509.IPAddress(ipaddress.ip_address(name)))
        except ValueError:
            out.append(x509.DNSName(name))
    return out


def _private_folder(folder: Path, notes: list[str]) -> None:
    """`folder` made, or made private: a key's folder others may write lets them swap the key."""
    folder.mkdir(parents=True, exist_ok=True, mode=0o700)
    mode = stat.S_IMODE(folder.stat().st_mode)
    if mode & 0o077:
        os.chmod(folder, 0o700)
        notes.append(f"{folder} was open to others (mode {mode:04o}): now 0700")


def _write(path: Path, data: bytes, mode: int) -> None:
    """Written whole, created with `mode` (never readable by others in between)."""
    tmp = path.with_name(path.name + ".tmp")
    tmp.unlink(missing_ok=True)
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, mode)
    with os.fdopen(fd, "wb") as f:
        f.write(data)
    os.replace(tmp, path)


@dataclass
class Own:
    """The station's certificate and key, and what making them sure changed (for the journal)."""

    cert: Path
    key: Path
    notes: list[str] = field(default_factory=list)
    private_key: rsa.RSAPrivateKey | None = None  # the key as loaded or made here (loading checks it: 60 ms)


def station_certificate(folder: Path, uri: str, names: list[str], station: str,
                        now: dt.datetime | None = None) -> Own:
    """The station's certificate and key in `folder`/pki/own, made or made right (see above)."""
    from asyncua.crypto.cert_gen import generate_self_signed_app_certificate  # asyncua only for OPC UA

    now = now or dt.datetime.now(dt.UTC)
    own_dir = folder / PKI / "own"
    own = Own(own_dir / "cert.der", own_dir / "key.pem")
    _private_folder(folder / PKI, own.notes)
    _private_folder(own_dir, own.notes)
    if not own.key.exists() and (folder / OLD_KEY).exists():  # keep the key clients know
        os.replace(folder / OLD_KEY, own.key)
        if (folder / OLD_CERT).exists():
            os.replace(folder / OLD_CERT, own.cert)
        own.notes.append(f"certificate and key moved from the station folder to {own_dir}")
    if own.key.exists():
        mode = stat.S_IMODE(own.key.stat().st_mode)
        if mode & 0o077:
            os.chmod(own.key, 0o600)
            own.notes.append(f"{own.key} was readable by others (mode {mode:04o}): now 0600")
        key = serialization.load_pem_private_key(own.key.read_bytes(), password=None)
        if not isinstance(key, rsa.RSAPrivateKey):
            raise ValueError(f"{own.key}: not an RSA key")
    else:
        key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
        _write(own.key, key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                          serialization.NoEncryption()), 0o600)
    wanted = _general_names(uri, names)
    why = _renew(own.cert, key, wanted, now)
    if why:
        cert = generate_self_signed_app_certificate(key, f"NetPlc Station {station}", {}, wanted,
                                                    [ExtendedKeyUsageOID.SERVER_AUTH], days=365 * YEARS)
        _write(own.cert, cert.public_bytes(serialization.Encoding.DER), 0o644)
        own.notes.append(f"certificate made ({why}) naming {', '.join(names)}; thumbprint "
                         f"{thumbprint(own.cert.read_bytes())}")
    own.private_key = key
    return own


def _renew(path: Path, key: rsa.RSAPrivateKey, wanted: list[x509.GeneralName], now: dt.datetime) -> str:
    """Why the certificate at `path` must be made again; "" when it is right."""
    if not path.exists():
        return "none yet"
    try:
        cert = x509.load_der_x509_certificate(path.read_bytes())
        names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    except (ValueError, x509.ExtensionNotFound) as e:
        return f"the old one is not usable: {e}"
    if cert.public_key().public_numbers() != key.public_key().public_numbers():
        return "the old one is not of this key"
    if cert.not_valid_after_utc - RENEW_BEFORE < now:
        return f"the old one expires {cert.not_valid_after_utc:%Y-%m-%d}"
    if set(names) != set(wanted):
        return "the host's names changed"
    return ""


class TrustList:
    """The client certificates the station trusts (`pki/trusted/`) and those it refused."""

    def __init__(self, folder: Path) -> None:
        self.trusted_dir = folder / PKI / "trusted"
        self.rejected_dir = folder / PKI / "rejected"
        self._seen: tuple[int, frozenset[str]] | None = None  # (folder mtime, thumbprints)

    def trusted(self) -> frozenset[str]:
        """The thumbprints in trusted/, read again when the folder changed."""
        try:
            mtime = self.trusted_dir.stat().st_mtime_ns
        except OSError:
            return frozenset()
        if self._seen is None or self._seen[0] != mtime:
            prints = set()
            for path in self._files(self.trusted_dir):
                try:
                    prints.add(thumbprint(load_der(path)))
                except (OSError, ValueError):
                    logger.exception("%s: not a certificate, not trusted", path)
            self._seen = (mtime, frozenset(prints))
        return self._seen[1]

    def is_trusted(self, der: bytes) -> bool:
        return thumbprint(der) in self.trusted()

    def reject(self, der: bytes) -> Path | None:
        """A copy of the refused certificate in rejected/: its path if new (journal it), else None."""
        path = self.rejected_dir / f"{thumbprint(der)}.der"
        if path.exists():
            return None
        self.rejected_dir.mkdir(parents=True, exist_ok=True)
        if len(self._files(self.rejected_dir)) >= REJECTED_AT_MOST:
            logger.warning("%s holds %d certificates: %s not kept", self.rejected_dir, REJECTED_AT_MOST,
                           path.name)
            return None
        _write(path, der, 0o644)
        return path

    def trust(self, which: str) -> tuple[Path, bytes]:
        """Trust a certificate: `which` is a certificate file or the thumbprint of one in
        rejected/ (any case, with or without colons). Its new path in trusted/ and its DER."""
        source = Path(which)
        if source.is_file():
            try:
                der = load_der(source)
            except ValueError as e:
                raise TrustError(f"{source}: not a certificate ({e})") from None
        else:
            wanted = which.replace(":", "").replace(" ", "").upper()
            found = [p for p in self._files(self.rejected_dir) if p.stem.upper() == wanted]
            if not found:
                raise TrustError(f"no certificate {which!r} in {self.rejected_dir} (nor a file of that name)")
            source = found[0]
            der = load_der(source)
        self.trusted_dir.mkdir(parents=True, exist_ok=True)
        target = self.trusted_dir / f"{thumbprint(der)}.der"
        if source.parent == self.rejected_dir:
            shutil.move(source, target)
        else:
            _write(target, der, 0o644)
        return target, der

    @staticmethod
    def _files(folder: Path) -> list[Path]:
        try:
            return [p for p in folder.iterdir() if p.suffix.lower() in CERT_SUFFIXES and p.is_file()]
        except OSError:
            return []
