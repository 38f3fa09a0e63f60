"""A station's OPC UA endpoint as a remote Program view uses it (`main.py monitor opc.tcp://...`).

The monitor is a user of that station, logged in over its endpoint: it reads NetPlc's memory and
forces (the read-only `NetPlc.Memory.*` and `NetPlc.Forces` variables, opcua.py) and acts only
through the station's methods (methods.py) and tag variables, which the station takes as commands
of its command layer with the session's user: checked against its one policy, journaled naming the
user (`opcua:<user>@<peer>`), answered once applied. Nothing here checks a role. What the user may
do is the station's answer (UserExecutable of each method, UserAccessLevel of each tag variable,
read again every few seconds), and each action's answer is the station's StatusCode mapped back to
the layer's `Reason`, so a view shows a refusal from here as it shows a local one.

A hot-standby pair's monitor is given both endpoints (`partner`): it follows the primary on its
own. Each read asks the Server's ServiceLevel too (Part 4 6.6.2: the primary 255, the standby
100); when the station it reads stops leading, or its link is lost, it logs in to the other with
the same user at once, and reads on. The partner's certificate must be known already (trusted in
`known_stations.json` by a first monitor of it), as a password is sent to no station unasked.

asyncua's client is asyncio: it runs on a thread of its own, callers get `concurrent.futures`
futures, and `snapshot` is NetPlc's memory as last read, polled every `period` (the view's refresh
period) and rebuilt only when something changed. A lost link is retried with a back-off.

Security, kept simple on purpose: the monitor takes Basic256Sha256 Sign&Encrypt whenever the
station offers it, which off loopback is all a station offers (opcua.py), and never sends a password
in clear to a station off loopback. The station's certificate is trusted on first use, as ssh does
with host keys: the first time, the user is shown its SHA-1 and SHA-256 fingerprints and decides;
`known_stations.json` in the user's config directory keeps it, and a station showing another
certificate later is refused until its line is removed from there (no CA chains, no revocation
lists). The monitor's own certificate and key (0600) are made in the same directory; the station
refuses it until an admin of the station trusts it (`python main.py opcua trust STATION THUMBPRINT`).
"""

from __future__ import annotations

import asyncio
import hashlib
import json
import logging
import os
import socket
import time
from collections.abc import Callable, Coroutine
from concurrent.futures import Future
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal
from urllib.parse import unquote, urlsplit

from asyncua import Client, ua
from asyncua.crypto.security_policies import SecurityPolicyBasic256Sha256
from cryptography.hazmat.primitives import serialization
from cryptography.hazmat.primitives.asymmetric import rsa
from cryptography.x509.oid import ExtendedKeyUsageOID

from app.authority import APPLIED, Action, Answer, Reason, Ticket
from app.publish.methods import METHODS
from app.publish.opcua import ANSWERS, application_uri, is_loopback, variant_type
from app.publish.pki import _general_names, _private_folder, _write, subject, thumbprint
from app.scada.tag import Tag
from netplc.address import parse_octal
from netplc.forcing import Force
from netplc.memory import Snapshot
from netplc.modbus import LoopThread

logger = logging.getLogger(__name__)

STATION_URI = "urn:netplc:station:"  # the station's namespace: this, then the station's name
TIMEOUT_S = 5.0
CLOSE_S = 2.0  # a logout the station does not answer within this is left to its session timeout
RIGHTS_EVERY_S = 2.0  # what the user may do is asked again this often (a role changed at the station)
RETRY_S = (0.5, 1.0, 2.0, 5.0, 10.0)  # back-off of reconnections
LEADS = 200  # a ServiceLevel from here up is a healthy server (Part 4 6.6.2.4.2): a pair's primary
KNOWN_STATIONS = "known_stations.json"
WRITE = 1 << ua.AccessLevel.CurrentWrite  # in a UserAccessLevel
REASONS = {int(code): reason for reason, code in ANSWERS.items()}  # the station's codes, read back
PARAMETER_TYPES = {ua.ObjectIds.String: ua.VariantType.String, ua.ObjectIds.Int32: ua.VariantType.Int32,
                   ua.ObjectIds.Double: ua.VariantType.Double}
METHOD_OF = {m.action: m.name for m in reversed(METHODS)}  # the station's method for each action
SIGNATURES = {m.name: tuple(PARAMETER_TYPES[kind] for _, _, kind in m.inputs) for m in METHODS}


class LoginError(Exception):
    """The station could not be reached, or refused the monitor or the login: words for the user."""


def config_dir() -> Path:
    """The user's configuration directory for NetPlc ($XDG_CONFIG_HOME/netplc, ~/.config/netplc)."""
    base = os.environ.get("XDG_CONFIG_HOME") or str(Path.home() / ".config")
    return Path(base) / "netplc"


def _pairs(digest: str) -> str:
    return ":".join(digest[i:i + 2] for i in range(0, len(digest), 2))


@dataclass(frozen=True)
class Certificate:
    """A station's certificate as it is shown to a person deciding whether to trust it."""

    der: bytes

    @property
    def sha1(self) -> str:
        return _pairs(thumbprint(self.der))

    @property
    def sha256(self) -> str:
        return _pairs(hashlib.sha256(self.der).hexdigest().upper())

    @property
    def subject(self) -> str:
        return subject(self.der)


@dataclass(frozen=True)
class Offer:
    """What a station's endpoint offers, as its discovery (GetEndpoints) says."""

    url: str
    certificate: Certificate | None  # None: the station offers no security (a loopback endpoint)


Verdict = Literal["known", "new", "changed"]


class KnownStations:
    """The station certificates this user trusts, one per endpoint (host and port): a JSON file."""

    def __init__(self, folder: Path | None = None) -> None:
        self.path = (folder or config_dir()) / KNOWN_STATIONS

    @staticmethod
    def key(url: str) -> str:
        return urlsplit(url).netloc.lower()

    def _read(self) -> dict[str, dict[str, str]]:
        try:
            return json.loads(self.path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            return {}
        except (OSError, ValueError) as e:
            raise LoginError(f"{self.path}: not readable ({e}): remove it or repair it") from None

    def verdict(self, url: str, certificate: Certificate) -> Verdict:
        known = self._read().get(self.key(url))
        if known is None:
            return "new"
        return "known" if known.get("sha256") == certificate.sha256 else "changed"

    def remember(self, url: str, certificate: Certificate) -> None:
        stations = self._read()
        stations[self.key(url)] = {"sha256": certificate.sha256, "subject": certificate.subject}
        _private_folder(self.path.parent, [])
        _write(self.path, (json.dumps(stations, indent=1, sort_keys=True) + "\n").encode(), 0o600)


def monitor_certificate(folder: Path | None = None) -> tuple[Path, Path, str]:
    """The monitor's own certificate and key (made once, the key 0600) and its application URI."""
    from asyncua.crypto.cert_gen import generate_self_signed_app_certificate

    own = (folder or config_dir()) / "monitor"
    cert, key_path = own / "cert.der", own / "key.pem"
    host = socket.gethostname()
    uri = f"urn:netplc:monitor:{host}"
    _private_folder(own.parent, [])
    _private_folder(own, [])
    if key_path.exists() and cert.exists():
        return cert, key_path, uri
    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    _write(key_path, key.private_bytes(serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8,
                                       serialization.NoEncryption()), 0o600)
    names = _general_names(uri, [host])
    made = generate_self_signed_app_certificate(key, f"NetPlc monitor {host}", {}, names,
                                                [ExtendedKeyUsageOID.CLIENT_AUTH], days=365 * 5)
    _write(cert, made.public_bytes(serialization.Encoding.DER), 0o644)
    return cert, key_path, uri


def _why(e: BaseException) -> str:
    if isinstance(e, ua.UaStatusCodeError):
        name, doc = ua.status_codes.get_name_and_doc(e.code)
        return f"{name}: {doc}"
    return str(e) or type(e).__name__


def answer_of(code: int) -> Answer:
    """The station's StatusCode for a command as the layer's answer."""
    if ua.StatusCode(code).is_good():
        return APPLIED
    name, doc = ua.status_codes.get_name_and_doc(code)
    return Answer(REASONS.get(code, Reason.FAILED), f"the station answered {name}: {doc}")


async def _offer(url: str) -> Offer:
    """What the station at `url` offers (GetEndpoints over a None channel, which stations serve
    for discovery); LoginError when it does not answer, or offers only what sends a password in
    clear off loopback."""
    try:
        endpoints = await Client(url, timeout=TIMEOUT_S).connect_and_get_server_endpoints()
    except (OSError, TimeoutError, ua.UaError) as e:
        raise LoginError(f"{url}: no answer ({_why(e)})") from None
    offer = Offer(url, None)
    for ep in endpoints:
        if ep.SecurityPolicyUri == SecurityPolicyBasic256Sha256.URI and ep.ServerCertificate and \
                ep.SecurityMode == ua.MessageSecurityMode.SignAndEncrypt:
            offer = Offer(url, Certificate(bytes(ep.ServerCertificate)))
    if offer.certificate is None and not is_loopback(url):
        raise LoginError(f"{url} offers no Basic256Sha256 Sign&Encrypt endpoint: a password is not "
                         "sent in clear to a station off loopback")
    return offer


class StationClient:
    """One logged-in session with a station, on a thread of its own: `discover()`, decide whether
    to trust the station's certificate (`KnownStations`), then `open()`, `close()` at the end."""

    def __init__(self, url: str, *, partner: str = "", folder: Path | None = None,
                 period: float = 0.1) -> None:
        """`folder` holds the monitor's own certificate and the known stations (config_dir());
        `partner`: the endpoint of the other station of a hot-standby pair, followed to when it leads."""
        self.url = url
        self.partner = partner
        self.service_level = LEADS  # the Server's, as last read
        self.switches = 0  # times the monitor followed the pair's primary to the other station
        self.switched = ""  # the last of those, in words for the user ("" before any)
        self.server = ""  # the ApplicationUri of the station logged in to: a pair's ends in its letter
        self.offer: Offer | None = None
        self.user = ""
        self._password = ""
        self.folder = folder
        self.period = period
        self.station = ""  # the station's name, from its namespace (once logged in)
        self.snapshot: Snapshot | None = None  # NetPlc's memory as last read
        self.executable: dict[str, bool] = {}  # method name -> may the user call it (the station's answer)
        self.writable: dict[str, bool] = {}  # tag name -> may the user write it (UserAccessLevel)
        self.rights = 0  # bumped whenever those answers change
        self.reads = 0
        self.error = ""  # why the link is down ("" while it is up)
        self._watched: set[str] = set()  # tags whose UserAccessLevel is asked (added to from the GUI)
        self._client: Client | None = None
        self._ns = 0
        self._raw: tuple[object, ...] = ()
        self._loop = LoopThread(f"monitor-{urlsplit(self.url).netloc}")
        self._task: asyncio.Task[None] | None = None
        # called on the client's thread when the snapshot or the link's state changed
        self.changed: Callable[[], None] = lambda: None

    # --- from any thread ----------------------------------------------------------------------

    def discover(self) -> Future[Offer]:
        """What the station offers (GetEndpoints over a None channel, which stations serve for
        discovery): its certificate to trust, or none on a loopback endpoint; LoginError if none."""
        if self._loop.loop is None:
            self._loop.start()
        return self._submit(self._discover())

    def open(self, user: str, password: str) -> Future[None]:
        """Log in as `user` to the station `discover()` found (LoginError says why not; call again
        to retry), then keep reading memory."""
        assert self.offer is not None, "discover() first"
        self.user, self._password = user, password
        return self._submit(self._open())

    def close(self) -> None:
        """Log out and stop (waits for the logout at most CLOSE_S)."""
        if self._loop.loop is None:
            return
        try:
            self._submit(self._close()).result(CLOSE_S)
        except Exception:  # no log: the session may be gone already, with nothing to log out
            logger.debug("logout at close failed", exc_info=True)
        self._loop.stop()

    def may(self, action: Action) -> bool | None:
        """May the user do `action`? The station's answer for its method (UserExecutable); None
        until it answered."""
        return self.executable.get(METHOD_OF.get(action, ""))

    def may_write(self, name: str) -> bool | None:
        """May the user write the tag `name`? The station's answer (UserAccessLevel), asked from
        the first time this is asked; None until it answered."""
        self._watched.add(name)  # asked at the next read
        return self.writable.get(name)

    def call(self, method: str, *args: object) -> Ticket:
        """Call one of the station's methods (methods.py) with plain values (None: a Null)."""
        variants = [ua.Variant() if a is None else ua.Variant(a, kind)
                    for a, kind in zip(args, SIGNATURES[method])]
        return self._command(self._call(method, variants))

    def write_tag(self, tag: Tag, phy: float) -> Ticket:
        """Write a tag's variable, in the variable's own type (opcua.variant_type)."""
        kind = variant_type(tag)
        value: object = bool(phy) if kind is ua.VariantType.Boolean else \
            float(phy) if kind in (ua.VariantType.Double, ua.VariantType.Float) else round(phy)
        return self._command(self._write(tag.name, ua.Variant(value, kind)))

    def state(self) -> str:
        """What the client is doing, in a line."""
        if self.error:
            return f"link down: {self.error}; retrying"
        snap = self.snapshot
        if snap is None:
            return f"logging in to {self.url} as {self.user}…"
        return (f"{self.user} at {self.where()}: NetPlc {snap.state}, scan {snap.scan}, "
                f"{self.reads} reads" + (f"; {self.switched}" if self.switched else ""))

    def where(self) -> str:
        """The station logged in to, with its letter when it is one of a pair ("pair B")."""
        letter = self.server.removeprefix(f"{application_uri(self.station)}:") if self.station else ""
        name = self.station or self.url
        return f"{name} {letter}" if letter and letter != self.server else name

    # --- on the client's loop -------------------------------------------------------------------

    def _submit(self, coro: Coroutine[Any, Any, Any]) -> Future[Any]:
        assert self._loop.loop is not None
        return asyncio.run_coroutine_threadsafe(coro, self._loop.loop)

    def _command(self, coro: Coroutine[Any, Any, int]) -> Ticket:
        """A command sent to the station; its future answers as the station's layer did."""
        ticket: Ticket = Future()
        if self._loop.loop is None:
            coro.close()
            ticket.set_result(Answer(Reason.FAILED, "not sent: the monitor is closed"))
            return ticket

        def done(sent: Future[int]) -> None:
            try:
                ticket.set_result(answer_of(sent.result()))
            except Exception as e:  # the link broke: whether it was done, the station's journal says
                logger.exception("%s: no answer to a command", self.url)
                ticket.set_result(Answer(Reason.FAILED, f"no answer from the station ({_why(e)}): its "
                                                        "journal says whether it was done"))

        self._submit(coro).add_done_callback(done)
        return ticket

    async def _discover(self) -> Offer:
        self.offer = await _offer(self.url)
        return self.offer

    async def _open(self) -> None:
        try:
            await self._connect()
        except LoginError:
            raise
        except (OSError, TimeoutError, ua.UaError) as e:
            raise LoginError(self._refused(e)) from None
        self._task = asyncio.get_running_loop().create_task(self._run())

    def _refused(self, e: BaseException) -> str:
        """Why a login failed, and what to do about it."""
        if isinstance(e, ua.UaStatusCodeError) and e.code in (
                ua.StatusCodes.BadUserAccessDenied, ua.StatusCodes.BadIdentityTokenRejected,
                ua.StatusCodes.BadIdentityTokenInvalid, ua.StatusCodes.BadUserSignatureInvalid):
            return (f"{self.url} refused the login of {self.user!r} ({_why(e)}): a wrong user or password, "
                    "or too many failed logins from here (the station then waits before it answers)")
        secure = self.offer is not None and self.offer.certificate is not None
        if secure and not isinstance(e, ua.UaStatusCodeError):
            cert, _, _ = monitor_certificate(self.folder)
            thumb = thumbprint(cert.read_bytes())
            return (f"{self.url} closed the secure channel ({_why(e)}). If it does not trust this monitor "
                    f"yet, an admin of the station trusts its certificate (thumbprint {thumb}) with: "
                    f"python main.py opcua trust STATION {thumb}")
        return f"{self.url}: {_why(e)}"

    async def _connect(self) -> None:
        assert self.offer is not None
        # asyncua probes the link every `watchdog_intervall` and gives it that long to answer (1 s by
        # default, which a loaded PC misses: a session dropped for nothing); a lost link is found by
        # the reads here, a closed one at once
        client = Client(self.url, timeout=TIMEOUT_S, watchdog_intervall=TIMEOUT_S)
        client.name = f"NetPlc monitor ({self.user})"
        certificate = self.offer.certificate
        if certificate is not None:
            cert, key, uri = await asyncio.to_thread(monitor_certificate, self.folder)
            client.application_uri = uri
            await client.set_security(SecurityPolicyBasic256Sha256, str(cert), str(key),
                                      server_certificate=certificate.der)
        client.set_user(self.user)
        client.set_password(self._password)
        connected = False
        try:
            await client.connect()
            spaces = await client.get_namespace_array()
            # the last: a pair's station has its ApplicationUri (the namespace's with its letter) at
            # index 1, as every server has, and the namespace of its nodes, the same on both, after it
            ours = [(i, s) for i, s in enumerate(spaces) if s.startswith(STATION_URI)]
            station = ours[-1] if ours else None
            if station is None:
                raise LoginError(f"{self.url} is not a NetPlc station (no {STATION_URI}... namespace)")
            self._ns, self.station = station[0], unquote(station[1].removeprefix(STATION_URI))
            self.server = spaces[1] if len(spaces) > 1 else ""
            self._client = client
            await self._ask_rights()
            await self._read()
            connected = True
        finally:
            if not connected:
                self._client = None
                try:
                    await client.disconnect()
                except Exception:  # no log: a session half made; closing it may fail too
                    logger.debug("closing a half-made session failed", exc_info=True)

    async def _close(self) -> None:
        if self._task is not None:
            self._task.cancel()
        client, self._client = self._client, None
        if client is not None:
            await client.disconnect()

    async def _run(self) -> None:
        """Read memory every period, the user's rights every few seconds; reconnect when the link
        is lost, with a back-off."""
        asked = time.monotonic()
        failures = 0
        while True:
            await asyncio.sleep(self.period)
            try:
                if self._client is None:
                    await self._connect()
                    asked = time.monotonic()
                await self._read()
                if self.partner and self.service_level < LEADS and await self._follow("it leads no more"):
                    asked = time.monotonic()
                    continue
                if self.error:
                    self.error = ""
                    self.changed()
                if time.monotonic() - asked >= RIGHTS_EVERY_S or not self._watched <= self.writable.keys():
                    asked = time.monotonic()
                    await self._ask_rights()
                self.error, failures = "", 0
            except (OSError, TimeoutError, ua.UaError, LoginError) as e:
                if _why(e) != self.error:
                    logger.warning("%s: %s", self.url, _why(e))  # once per cause, not every try
                if self.partner and failures == 0 and await self._follow(_why(e)):
                    continue
                await self._lost(_why(e), failures)
                failures += 1
            except Exception as e:  # not the link's fault: logged whole, then tried again the same way
                logger.exception("%s: reading the station failed", self.url)
                await self._lost(f"{type(e).__name__}: {e}", failures)
                failures += 1

    async def _follow(self, why: str) -> bool:
        """Log in to the pair's other station (its certificate known already); True once
        logged in there, False when it cannot be (the link to this one is then retried)."""
        try:
            there = await _offer(self.partner)
        except LoginError as e:
            logger.warning("%s: the pair's other station: %s", self.url, e)
            return False
        if there.certificate is not None and \
                KnownStations(self.folder).verdict(self.partner, there.certificate) != "known":
            self.error = (f"{self.url}: {why}; the pair's other station {self.partner} is not trusted yet: "
                          f"monitor it once to trust its certificate")
            return False
        left = self.where()
        self.error = f"{why}; switching to the pair's other station {self.partner}"
        self.changed()  # shown while it switches: nothing looks live from the station left
        old = self._client
        self._client = None
        if old is not None:
            try:
                await old.disconnect()
            except Exception:  # no log: the station left may be gone; its session times out there
                logger.debug("closing the session of the station left failed", exc_info=True)
        self.url, self.partner, self.offer = self.partner, self.url, there
        try:
            await self._connect()
        except (OSError, TimeoutError, ua.UaError, LoginError) as e:
            logger.warning("%s: logging in failed: %s", self.url, _why(e))
            return False
        self.switches += 1
        self.error = ""
        self.switched = f"switched from {left} at {time.strftime('%H:%M:%S')} ({why})"
        logger.info("following the pair's primary to %s (%s)", self.url, why)
        self.changed()
        return True

    async def _lost(self, why: str, failures: int) -> None:
        """The session is given up (said in `error`) and a new one tried after a back-off."""
        self.error = why
        self.changed()
        client, self._client = self._client, None
        if client is not None:
            try:
                await client.disconnect()
            except Exception:  # no log: the link is gone (its loss is said); closing may fail too
                logger.debug("closing a lost session failed", exc_info=True)
        await asyncio.sleep(RETRY_S[min(failures, len(RETRY_S) - 1)])

    def _node(self, name: str) -> ua.NodeId:
        return ua.NodeId(name, self._ns)

    async def _read(self) -> None:
        client = self._client
        assert client is not None
        names = ("NetPlc.Tick", "NetPlc.State", "NetPlc.Memory.Bits", "NetPlc.Memory.Data", "NetPlc.Forces")
        nodes = [self._node(n) for n in names] + [ua.NodeId(ua.ObjectIds.Server_ServiceLevel)]
        *values, level = await client.uaclient.read_attributes(nodes, ua.AttributeIds.Value)
        for dv in values:
            if dv.StatusCode is not None and not dv.StatusCode.is_good():
                raise ua.UaStatusCodeError(dv.StatusCode.value)
        served = level.Value.Value if level.Value is not None else None
        self.service_level = LEADS if served is None else int(served)
        raw = tuple(dv.Value.Value if dv.Value is not None else None for dv in values)
        self.reads += 1
        if raw == self._raw:
            return
        self._raw = raw
        tick, state, bits, data, forces = raw
        when = values[2].SourceTimestamp
        self.snapshot = Snapshot(tuple(bits or b""), bytes(data or b""), int(tick or 0), time.monotonic(),
                                 when.timestamp() if when is not None else time.time(), str(state or ""),
                                 self._forces(str(forces or "[]")))
        self.changed()

    def _forces(self, text: str) -> tuple[Force, ...]:
        try:
            return tuple(Force(f["kind"], parse_octal(f["address"]), int(f["value"]), str(f.get("user", "")))
                         for f in json.loads(text))
        except (ValueError, KeyError, TypeError):
            logger.exception("%s: NetPlc.Forces not understood: %.200s", self.url, text)
            return ()

    async def _ask_rights(self) -> None:
        """The station's answers: may this user call each method, write each watched tag?"""
        client = self._client
        if client is None:
            return
        methods = [m.name for m in METHODS]
        tags = sorted(self._watched)
        calls = await client.uaclient.read_attributes([self._node(f"Station.{m}") for m in methods],
                                                      ua.AttributeIds.UserExecutable)
        levels = await client.uaclient.read_attributes([self._node(f"Tags.{t}") for t in tags],
                                                       ua.AttributeIds.UserAccessLevel) if tags else []
        executable = {m: bool(dv.Value and dv.Value.Value) for m, dv in zip(methods, calls)}
        writable = {t: bool(dv.Value and dv.Value.Value is not None and dv.Value.Value & WRITE)
                    for t, dv in zip(tags, levels)}
        if (executable, writable) != (self.executable, self.writable):
            self.executable, self.writable = executable, writable
            self.rights += 1

    async def _call(self, method: str, args: list[ua.Variant]) -> int:
        client = self._client
        if client is None:
            raise ConnectionError(f"not connected: {self.error or 'logging in'}")
        request = ua.CallMethodRequest(ObjectId=self._node(self.station),
                                       MethodId=self._node(f"Station.{method}"), InputArguments=args)
        result = (await client.uaclient.call([request]))[0]
        return result.StatusCode.value

    async def _write(self, name: str, variant: ua.Variant) -> int:
        client = self._client
        if client is None:
            raise ConnectionError(f"not connected: {self.error or 'logging in'}")
        codes = await client.uaclient.write_attributes([self._node(f"Tags.{name}")], [ua.DataValue(variant)])
        return codes[0].value

