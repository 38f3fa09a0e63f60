"""The OPC UA server off loopback: sessions only over Basic256Sha256 Sign&Encrypt whatever the client
asks, a private key of its own, a certificate naming the host, a trust list of client certificates
with a command to trust one, and logins that back off. Bound to 0.0.0.0, reached on 127.0.0.1."""

from __future__ import annotations

import asyncio
import os
import socket
import stat
import statistics
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import pytest
from asyncua import Client, ua
from asyncua.crypto import uacrypto
from asyncua.crypto.cert_gen import (
    dump_private_key_as_pem,
    generate_private_key,
    setup_self_signed_certificate,
)
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from cryptography import x509
from cryptography.x509.oid import ExtendedKeyUsageOID

from app.authority.users import Scrypt, Users
from app.publish.pki import thumbprint
from app.publish.trust import main as trust
from tests.app.conftest import REPO
from tests.app.publish.conftest import STATION_URI, demo_with, free_port, tag_node

CLIENT_KEY: list[object] = []  # made once


class Secure:
    """The demo station serving OPC UA on every address, and how a client reaches it."""

    def __init__(self, folder: Path) -> None:
        self.port = free_port()
        self.runtime = demo_with(folder, f'[opcua]\nenabled = true\n'
                                         f'endpoint = "opc.tcp://0.0.0.0:{self.port}/netplc/"\n'
                                         'writable = ["TEMP_SP"]\ncertificate_names = ["scada.plant"]\n',
                                 language="en")
        self.records: list = []
        self.runtime.subscribe(self.records.append)
        self.url = f"opc.tcp://127.0.0.1:{self.port}/netplc/"
        self.folder = folder
        self.own = folder / "pki" / "own"
        self.keys: dict[bytes, object] = {}  # the client keys loaded, by their PEM

    def client_certificate(self, name: str) -> tuple[Path, Path]:
        """A certificate of the test's own, as asyncua's `setup_self_signed_certificate` makes it,
        on the file's one client key (a new RSA key is a random 0.1-0.5 s of CPU)."""
        key, cert = self.folder.parent / f"{name}-key.pem", self.folder.parent / f"{name}-cert.der"
        if not CLIENT_KEY:
            CLIENT_KEY.append(generate_private_key())
        key.write_bytes(dump_private_key_as_pem(CLIENT_KEY[0]))
        asyncio.run(setup_self_signed_certificate(key, cert, f"urn:test:{name}", "localhost",
                                                  [ExtendedKeyUsageOID.CLIENT_AUTH], {"commonName": name}))
        return cert, key

    async def client(self, cert: Path, key: Path, user: str | None = None, password: str = "") -> Client:
        """A client of certificate `cert` over Basic256Sha256 Sign&Encrypt, as asyncua's
        `Client.set_security` makes it, but with the key loaded once: asyncua loads it at
        every client, and loading a key checks it (80 ms of CPU, a third of this file's)."""
        client = Client(self.url, timeout=30)
        client.application_uri = f"urn:test:{cert.stem.removesuffix('-cert')}"
        pem = key.read_bytes()
        if pem not in self.keys:
            self.keys[pem] = await uacrypto.load_private_key(pem, extension="pem")
        station = await uacrypto.load_certificate(str(self.own / "cert.der"))
        client.security_policy = SecurityPolicyBasic256Sha256(
            station, await uacrypto.load_certificate(str(cert)), self.keys[pem],
            ua.MessageSecurityMode.SignAndEncrypt)
        client.uaclient.set_security(client.security_policy)
        if user is not None:
            client.set_user(user)
            client.set_password(password)
        return client

    def texts(self, part: str) -> list[str]:
        return [r.text for r in self.records if part in (r.text or "")]


@pytest.fixture(scope="module")
def shared(tmp_path_factory: pytest.TempPathFactory) -> Iterator[Secure]:
    station = Secure(tmp_path_factory.mktemp("secure") / "station")
    yield station
    station.runtime.stop()


@pytest.fixture
def secure(shared: Secure) -> Secure:
    """One station for the module's tests that leave its logins as they found them (each its own
    client certificate), its records from the test's start."""
    shared.records.clear()
    return shared


@pytest.fixture
def own(tmp_path: Path) -> Iterator[Secure]:
    """A station of the test's own, whose logins it may hold back."""
    station = Secure(tmp_path / "station")
    yield station
    station.runtime.stop()


def run(coro: object) -> object:
    return asyncio.run(coro)  # type: ignore[arg-type]


def test_a_none_channel_serves_discovery_only_whatever_the_client_asks(secure: Secure) -> None:
    async def anonymous_over_none() -> int:
        client = Client(secure.url, timeout=30)  # no set_security: SecurityPolicy None
        try:
            await client.connect()
        except ua.UaStatusCodeError as e:
            return e.code
        await client.disconnect()
        return ua.StatusCodes.Good

    async def with_password_over_none() -> int:
        client = Client(secure.url, timeout=30)
        client.set_user("operator")
        client.set_password("operator")
        try:
            await client.connect()
        except ua.UaStatusCodeError as e:
            return e.code
        return ua.StatusCodes.Good

    async def endpoints() -> list[tuple[str, int]]:
        client = Client(secure.url, timeout=30)
        return [(e.SecurityPolicyUri.split("#")[1], e.SecurityMode)
                for e in await client.connect_and_get_server_endpoints()]

    for _ in range(3):
        assert run(anonymous_over_none()) == ua.StatusCodes.BadSecurityPolicyRejected
    assert run(with_password_over_none()) == ua.StatusCodes.BadSecurityPolicyRejected
    # discovery over None is how standard clients learn the one endpoint and its certificate
    assert run(endpoints()) == [("Basic256Sha256", ua.MessageSecurityMode.SignAndEncrypt)]
    refused = secure.texts("refused open a session")
    assert len(refused) == 1 and "discovery only" in refused[0]  # journaled once a minute
    assert not secure.texts("log in")  # no password reached the station's users


def test_the_key_is_private_and_the_certificate_names_the_host(secure: Secure) -> None:
    key = secure.own / "key.pem"
    assert stat.S_IMODE(key.stat().st_mode) == 0o600
    assert stat.S_IMODE(secure.own.stat().st_mode) == 0o700
    assert stat.S_IMODE((secure.folder / "pki").stat().st_mode) == 0o700
    cert = x509.load_der_x509_certificate((secure.own / "cert.der").read_bytes())
    names = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value
    dns = set(names.get_values_for_type(x509.DNSName))
    assert {socket.gethostname(), socket.getfqdn(), "scada.plant"} <= dns and "0.0.0.0" not in dns
    # the demo's Russian name percent-encoded (RFC 3987 3.1): a certificate's URI is ASCII
    encoded = "urn:netplc:station:%D0%94%D0%B5%D0%BC%D0%BE-%D1%81%D1%82%D0%B0%D0%BD%D1%86%D0%B8%D1%8F"
    assert names.get_values_for_type(x509.UniformResourceIdentifier) == [STATION_URI] == [encoded]


def test_an_untrusted_client_is_refused_kept_journaled_once_and_trusted_by_the_command(
        secure: Secure, capsys: pytest.CaptureFixture[str]) -> None:
    cert, key = secure.client_certificate("console")
    thumb = thumbprint(cert.read_bytes())

    async def connect() -> object:
        client = await secure.client(cert, key, "operator", "operator")
        try:
            async with client:
                sp = await tag_node(client, "TEMP_SP")
                await sp.write_value(ua.DataValue(ua.Variant(61.0, ua.VariantType.Double)))
                return await sp.read_value()
        except (TimeoutError, ua.UaError, OSError) as e:
            return e

    for _ in range(2):
        refused = run(connect())
        assert isinstance(refused, Exception), refused
    rejected = secure.folder / "pki" / "rejected" / f"{thumb}.der"
    assert rejected.read_bytes() == cert.read_bytes()
    journaled = secure.texts("client certificate refused")
    assert len(journaled) == 1 and thumb in journaled[0] and "CN=console" not in journaled[0]
    assert "console" in journaled[0] and "main.py opcua trust" in journaled[0]

    done = subprocess.run([sys.executable, "main.py", "opcua", "trust", str(secure.folder), thumb.lower()],
                          cwd=REPO, capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert not rejected.exists() and (secure.folder / "pki" / "trusted" / f"{thumb}.der").exists()
    assert run(connect()) == pytest.approx(61.0, abs=0.05)  # trusted at the next connection
    written = [r for r in secure.records if r.kind == "operator" and "TEMP_SP" in r.text]
    assert written and written[-1].source.startswith("opcua:operator@127.0.0.1:")

    assert trust(["trust", str(secure.folder), "00FF"]) == 1  # the command's function: the process is above
    assert "no certificate '00FF'" in capsys.readouterr().err


def test_logins_back_off_are_journaled_and_unknown_names_take_the_time_of_wrong_passwords(
        own: Secure) -> None:
    secure = own
    cert, key = secure.client_certificate("console")
    assert trust(["trust", str(secure.folder), str(cert)]) == 0  # the command's process is the test above's
    users = Users(secure.folder)  # every user at a cost well above the channel's own work (~5 ms)
    for user in list(users.users.values()):
        users.remove(user.name)
        users.add(user.name, user.role, user.name, Scrypt(n=2**12))
    logins = next(p for p in secure.runtime.publishers if hasattr(p, "server")).server.users.logins
    logins.monotonic = lambda: 1000.0  # the logins' clock stands still: a loaded machine's slow
    # secure connections cannot outlast the one-second back-off

    async def login(user: str, password: str) -> int:
        client = await secure.client(cert, key, user, password)
        try:
            async with client:
                return ua.StatusCodes.Good
        except ua.UaStatusCodeError as e:
            return e.code

    # three failures, then even the right password waits out the back-off
    assert [run(login("operator", "guess")) for _ in range(3)] == [ua.StatusCodes.BadUserAccessDenied] * 3
    assert run(login("operator", "operator")) == ua.StatusCodes.BadUserAccessDenied
    failed = [r for r in secure.records if r.kind == "operator" and "refused log in" in r.text]
    assert [r.source.rsplit(":", 1)[0] for r in failed] == ["opcua operator@127.0.0.1"] * 2
    assert "wrong user name or password" in failed[0].text and "refused for" in failed[1].text

    logins.free = 1000  # no back-off: measure the refusals themselves

    async def activations() -> tuple[list[float], list[float]]:
        """ActivateSession alone, again and again on one secure channel and session."""
        client = await secure.client(cert, key)
        await client.connect_socket()
        try:
            await client.send_hello()
            await client.open_secure_channel()
            await client.create_session()
            times: dict[str, list[float]] = {"nobody": [], "operator": []}
            for _ in range(9):
                for user in times:
                    t0 = time.perf_counter()
                    with pytest.raises(ua.UaStatusCodeError):
                        await client.activate_session(username=user, password="guess")
                    times[user].append(time.perf_counter() - t0)
            return times["nobody"], times["operator"]
        finally:
            client.disconnect_socket()

    unknown, wrong = run(activations())
    # pair by pair (taken in turn, so the shared machine's drift hits both): before the stand-in an
    # unknown name was refused about 10x faster than a wrong password at the default cost (n 2**14),
    # 5x at n 2**12 (a ratio of 0.21, measured without the stand-in); the band is wide because a
    # loaded machine stretches single pairs, while a name told apart shows as a ratio near 0.2
    ratio = statistics.median(u / w for u, w in zip(unknown, wrong, strict=True))
    assert 0.5 < ratio < 2.0, (unknown, wrong)


def test_a_key_readable_by_others_is_made_private_and_old_files_are_kept(tmp_path: Path) -> None:
    """Files of a station from before the pki folder move there (clients that trust the
    certificate go on trusting it), and a key others can read is made private, journaled."""
    from app.publish.pki import station_certificate

    folder = tmp_path / "station"
    folder.mkdir()
    first = station_certificate(folder, "urn:netplc:station:S", ["plant-pc"], "S")
    made = first.cert.read_bytes()
    os.replace(first.key, folder / "opcua-key.pem")
    os.replace(first.cert, folder / "opcua-cert.der")
    os.chmod(folder / "opcua-key.pem", 0o644)
    again = station_certificate(folder, "urn:netplc:station:S", ["plant-pc"], "S")
    assert again.cert.read_bytes() == made
    assert stat.S_IMODE(again.key.stat().st_mode) == 0o600
    assert any("moved" in n for n in again.notes) and any("readable by others" in n for n in again.notes)
    assert not any("certificate made" in n for n in again.notes)  # the same certificate
    renamed = station_certificate(folder, "urn:netplc:station:S", ["plant-pc", "10.1.2.3"], "S")
    assert any("the host's names changed" in n for n in renamed.notes)
    cert = x509.load_der_x509_certificate(renamed.cert.read_bytes())
    ips = cert.extensions.get_extension_for_class(x509.SubjectAlternativeName).value.get_values_for_type(
        x509.IPAddress)
    assert [str(ip) for ip in ips] == ["10.1.2.3"]


def test_the_trust_command_names_bad_input(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    """The command's function (its process, exit code and all, is the untrusted client's test's)."""
    from tests.app.conftest import copy_demo

    station = copy_demo(tmp_path / "station")
    junk = tmp_path / "junk.der"
    junk.write_bytes(b"not a certificate")
    for arg, words in ((str(junk), "not a certificate"), ("ABCDEF", "no certificate 'ABCDEF'")):
        assert trust(["trust", str(station), arg]) == 1
        err = capsys.readouterr().err
        assert err.startswith("opcua trust: ") and words in err, err
