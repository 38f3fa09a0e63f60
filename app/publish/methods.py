"""The station's OPC UA methods: run, stop and step NetPlc, force and unforce an address or a tag,
for a remote Program view (`main.py monitor opc.tcp://...`) acting as a logged-in user of the station;
acknowledge and shelve alarms, write a form's bit or word and a faceplate's tag, for a remote
console (`main.py console`).

Each call is the station's command (app/authority/) with the session's user and peer: the layer
checks the role, journals it and answers once applied and committed; the call's StatusCode is the
layer's `Reason` mapped as for writes. asyncua passes a method neither the session nor the user,
so the OPC UA server takes these calls in the session's Call service (opcua.py) and hands them
here; the nodes' own callbacks only refuse (a call that did not come through a session).
UserExecutable is answered per session from the same policy.
"""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from asyncua import Node, ua

from app.authority import Action, Commands, Reason, Source, Ticket, Who
from hmi_forms.elements.target import EngineTarget
from netplc.address import AddressError, parse_octal
from netplc.forcing import KINDS

StepLock = Callable[[], "threading.Lock | None"]  # the scan thread's lock; None while not started


@dataclass(frozen=True)
class Method:
    name: str
    action: Action
    inputs: tuple[tuple[str, str, int], ...] = ()  # (name, description, DataType: an ObjectIds number)
    description: str = ""


_STRING, _INT32, _DOUBLE = ua.ObjectIds.String, ua.ObjectIds.Int32, ua.ObjectIds.Double
KIND, ADDRESS, TAG = ("Kind", "bit, byte or word", _STRING), ("Address", "octal, as 04010", _STRING), \
    ("Name", "the tag's name, as in tags.csv", _STRING)
LABEL = ("Label", "the form element's words for what it writes (journaled); empty: none", _STRING)
ROLE = ("Role", "the form element's Role: it may ask more than the station's policy, never less; "
                "empty: the policy's", _STRING)
ALARM = ("AlarmId", "the alarm's identity, as the Alarms folder names it (LEVEL.H, MSG3)", _STRING)
METHODS = (
    Method("Run", Action.RUN, description="Run NetPlc's program"),
    Method("Stop", Action.STOP, description="Stop NetPlc's program"),
    Method("Step", Action.STEP, description="One scan while NetPlc is stopped"),
    Method("IntoStandBy", Action.INTO_STANDBY,
           description="Hand the primary role of the hot-standby pair to the standby"),
    Method("Force", Action.FORCE, (KIND, ADDRESS, ("Value", "the forced value, a whole number; Null: its "
                                                             "present value (bumpless)", _INT32)),
           "Force an address to a value (force > program > live)"),
    Method("Unforce", Action.UNFORCE, (KIND, ADDRESS), "Remove the force of an address"),
    Method("ForceTag", Action.FORCE, (TAG, ("Value", "in the tag's physical units; Null: its present "
                                                     "value (bumpless)", _DOUBLE)),
           "Force a tag (its bit, or all its words) to a physical value"),
    Method("UnforceTag", Action.UNFORCE, (TAG,), "Remove the force of a tag (all its words)"),
    Method("UnforceAll", Action.UNFORCE, description="Remove every force"),
    # the alarm summary's actions by alarm identity (the conditions' own methods are Part 9's: conditions.py)
    Method("Acknowledge", Action.ACKNOWLEDGE, (ALARM,), "Acknowledge an alarm"),
    Method("AcknowledgeAll", Action.ACKNOWLEDGE, description="Acknowledge every unacknowledged alarm"),
    Method("Shelve", Action.SHELVE, (ALARM, ("Reason", "why it is shelved (journaled)", _STRING),
                                     ("Seconds", "how long it stays shelved", _DOUBLE)),
           "Shelve an alarm for a while (ISA-18.2): it neither sounds nor shows until then"),
    Method("Unshelve", Action.UNSHELVE, (ALARM,), "Return a shelved alarm to the summary"),
    Method("Silence", Action.SILENCE, description="Silence the horn; the alarms stay unacknowledged"),
    # what a remote console's form elements write (a raw NetPlc address, as the local workstation's do)
    Method("WriteBit", Action.WRITE, (ADDRESS, ("Value", "0 or 1", _INT32), LABEL, ROLE),
           "Write an I/O or HMI bit as an operator's form element does"),
    Method("WriteWord", Action.WRITE, (ADDRESS, ("Value", "the raw word, 0..65535", _INT32), LABEL, ROLE),
           "Write a data word as an operator's form element does"),
    # what a remote console's faceplate writes: the tag, in its units, checked against its range
    Method("WriteTag", Action.WRITE, (TAG, ("Value", "in the tag's physical units (a bit tag: 0 or 1)",
                                            _DOUBLE)),
           "Write a tag's physical value as an operator's faceplate does"),
)


class StationMethods:
    def __init__(self, commands: Commands, step_lock: StepLock, answers: dict[Reason, int]) -> None:
        self.commands = commands
        self.step_lock = step_lock
        self.answers = answers
        self.by_node: dict[ua.NodeId, Method] = {}
        self.target = EngineTarget(commands, lambda _user: Who("", Source.OPCUA))  # `who` is passed

    async def add(self, parent: Node, idx: int) -> None:
        for method in METHODS:
            args = [ua.Argument(Name=name, DataType=ua.NodeId(kind), ValueRank=-1,
                                Description=ua.LocalizedText(text)) for name, text, kind in method.inputs]
            nodeid, name = ua.NodeId(f"Station.{method.name}", idx), ua.QualifiedName(method.name, idx)
            node = await parent.add_method(nodeid, name, _not_through_a_session, [], [])
            await node.write_attribute(ua.AttributeIds.Description,
                                       ua.DataValue(ua.Variant(ua.LocalizedText(method.description))))
            if args:  # made here, not by asyncua, for a NodeId that stays the same at every start
                prop = await node.add_property(ua.NodeId(f"Station.{method.name}.InputArguments", idx),
                                               ua.QualifiedName("InputArguments", 0), args,
                                               ua.VariantType.ExtensionObject, ua.ObjectIds.Argument)
                await prop.write_value_rank(ua.ValueRank.OneDimension)
                await prop.write_array_dimensions([len(args)])
            self.by_node[node.nodeid] = method

    def executable(self, who: Who, nodeid: ua.NodeId) -> bool | None:
        """May `who` call the method at `nodeid`? None when it is none of these."""
        method = self.by_node.get(nodeid)
        return None if method is None else self.commands.may(who, method.action)

    async def call(self, who: Who, request: ua.CallMethodRequest) -> ua.CallMethodResult:
        method = self.by_node[request.MethodId]
        args, result = arguments(request, len(method.inputs))
        if not result.StatusCode.is_good():
            return result
        return await answered(result, await self._ticket(who, method, args), self.answers)

    async def _ticket(self, who: Who, method: Method, args: list[object]) -> Ticket:
        commands = self.commands
        if method.name == "Run":
            return commands.run(who)
        if method.name == "Stop":
            return commands.stop(who)
        if method.name == "Step":  # waits for the scan in progress: off the server's loop
            return await asyncio.to_thread(commands.step, who, self.step_lock())
        if method.name == "IntoStandBy":
            return commands.into_standby(who)
        if method.name == "UnforceAll":
            return commands.unforce_all(who)
        if method.name in ("ForceTag", "UnforceTag", "WriteTag"):
            return self._tag(who, method, args)
        if method.name == "AcknowledgeAll":
            return commands.acknowledge_all(who)
        if method.name == "Silence":
            return commands.silence(who)
        if method.name in ("Acknowledge", "Shelve", "Unshelve"):
            return self._alarm(who, method, args)
        if method.name in ("WriteBit", "WriteWord"):
            return self._write(who, method, args)
        kind, address = args[0], args[1]
        target = f"{kind} {address}"
        try:
            if kind not in KINDS:
                raise ValueError(f"{kind!r} is not one of {', '.join(KINDS)}")
            addr = _octal(address)
            value = args[2] if method.name == "Force" else None
            if value is not None and (not isinstance(value, int) or isinstance(value, bool)):
                raise ValueError(f"{value!r} is not a whole number")
        except (AddressError, ValueError) as e:
            return commands.refuse(who, method.action, target, Reason.INVALID, str(e))
        if method.name == "Force":
            return commands.force(who, kind, addr, value)  # type: ignore[arg-type]
        return commands.unforce(who, kind, addr)  # type: ignore[arg-type]

    def _alarm(self, who: Who, method: Method, args: list[object]) -> Ticket:
        commands = self.commands
        alarm = args[0]
        if not isinstance(alarm, str):
            return commands.refuse(who, method.action, str(alarm), Reason.INVALID,
                                   commands.say("alarm id string"))
        if method.name == "Acknowledge":
            return commands.acknowledge(who, alarm)
        if method.name == "Unshelve":
            return commands.unshelve(who, alarm)
        reason, seconds = args[1], args[2]
        if not isinstance(reason, str) or not isinstance(seconds, (int, float)) or isinstance(seconds, bool):
            return commands.refuse(who, method.action, alarm, Reason.INVALID, commands.say("shelve args"))
        return commands.shelve(who, alarm, reason, float(seconds))

    def _write(self, who: Who, method: Method, args: list[object]) -> Ticket:
        address, value, label, role = args
        try:
            addr = _octal(address)
            top = 1 if method.name == "WriteBit" else 0xFFFF
            if not isinstance(value, int) or isinstance(value, bool) or not 0 <= value <= top:
                raise ValueError(f"{value!r} is not a whole number 0..{top}")
            if not isinstance(label, (str, type(None))) or not isinstance(role, (str, type(None))):
                raise ValueError("Label and Role are Strings")
        except (AddressError, ValueError) as e:
            return self.commands.refuse(who, method.action, str(address), Reason.INVALID, str(e))
        write = self.target.bit if method.name == "WriteBit" else self.target.word
        return write(who, addr, value, label or None, role or None)

    def _tag(self, who: Who, method: Method, args: list[object]) -> Ticket:
        commands, name = self.commands, args[0]
        if not isinstance(name, str):
            return commands.refuse(who, method.action, str(name), Reason.INVALID,
                                   commands.say("tag name string"))
        if method.name == "UnforceTag":
            return commands.unforce_tag(who, name)
        value = args[1]
        if method.name == "WriteTag":  # the layer checks the value's type and the tag's range
            return commands.write_tag(who, name, value)
        if value is not None and (not isinstance(value, (int, float)) or isinstance(value, bool)):
            return commands.refuse(who, method.action, name, Reason.INVALID,
                                   commands.say("no number", value=value))
        return commands.force_tag(who, name, None if value is None else float(value))


def _octal(address: object) -> int:
    """An Address argument, octal text (its DataType is String): a number a client sends instead
    is refused, not read as octal digits (an Int32 1000 would be bit 01000)."""
    if not isinstance(address, str):
        raise ValueError(f"{address!r} is not an address: octal text, as 04010")
    return parse_octal(address)


def arguments(request: ua.CallMethodRequest, count: int) -> tuple[list[Any], ua.CallMethodResult]:
    """A call's argument values and its result, already Bad_ArgumentsMissing or
    Bad_TooManyArguments when it does not bring `count` of them."""
    args = [v.Value for v in request.InputArguments or []]
    result = ua.CallMethodResult()
    result.InputArgumentResults = [ua.StatusCode() for _ in args]
    if len(args) != count:
        result.StatusCode = ua.StatusCode(ua.StatusCodes.BadArgumentsMissing if len(args) < count else
                                          ua.StatusCodes.BadTooManyArguments)
    return args, result


async def answered(result: ua.CallMethodResult, ticket: Ticket,
                   answers: dict[Reason, int]) -> ua.CallMethodResult:
    """`result` with the command layer's answer as its StatusCode: once applied and committed, or
    refused (`answers` maps the layer's `Reason` to a StatusCode)."""
    answer = await asyncio.wrap_future(ticket)
    result.StatusCode = ua.StatusCode(answers[answer.reason])
    return result


def _not_through_a_session(parent: ua.NodeId, *args: object) -> ua.StatusCode:
    return ua.StatusCode(ua.StatusCodes.BadUserAccessDenied)
