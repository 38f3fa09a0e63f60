"""What an OPC UA client learns of a tag besides its value, in the standard's own terms.

A tag is a variable of one of OPC UA Part 8's types, so that a SCADA client knows what it holds
without our documentation: a bit is a TwoStateDiscreteType (TrueState, FalseState), anything else
an AnalogItemType (EURange: PhyMin..PhyMax of tags.csv, what a client may write; InstrumentRange:
AppMin..AppMax, the raw range the conversion starts from; EngineeringUnits: the unit as an
EUInformation with its UNECE code). The type's properties carry the standard's BrowseNames in
namespace 0 and string NodeIds derived from the tag's (`Tags.LEVEL.EURange`), so a browse path
resolves and a NodeId is the same at every start. The nodes are built as AddNodesItems and added
in bulk (`tag_items`): a station of 10,000 tags is built in seconds, not minutes.

Also here, because the live variables and the archive's values must agree: the DataType of a tag's
variable and the StatusCode of a quality.
"""

from __future__ import annotations

import importlib.metadata
import logging
from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from asyncua import ua

from app.authority import write_range
from app.scada.quality import Quality
from app.scada.tag import Tag, TagType

logger = logging.getLogger(__name__)

UNECE_UNITS = "http://www.opcfoundation.org/UA/units/un/cefact"  # EUInformation.NamespaceUri (Part 8)
PRODUCT = "NetPlc Station"
PRODUCT_URI = "urn:netplc:station"  # the product's (each station's ApplicationUri names the station)
DISTRIBUTION = "netplc-station"

READ = 1 << ua.AccessLevel.CurrentRead
WRITE = 1 << ua.AccessLevel.CurrentWrite
HISTORY_READ = 1 << ua.AccessLevel.HistoryRead

STATUS = {Quality.GOOD: ua.StatusCodes.Good, Quality.INITIAL: ua.StatusCodes.BadWaitingForInitialData,
          Quality.STALE: ua.StatusCodes.UncertainLastUsableValue,
          Quality.COMM_FAIL: ua.StatusCodes.BadCommunicationError,
          Quality.NOT_RUNNING: ua.StatusCodes.BadOutOfService,
          Quality.FORCED: ua.StatusCodes.GoodLocalOverride,
          Quality.UNREACHABLE: ua.StatusCodes.BadNoCommunication}
CODES = [ua.StatusCode(STATUS[q]) for q in Quality]  # by quality code
SEVERITY = {1: 900, 2: 700, 3: 500, 4: 300}  # alarm priority -> OPC UA severity 1-1000

# A unit as tags.csv spells it -> its UNECE Recommendation 20 common code and name, as the OPC
# Foundation's UNECE_to_OPCUA table lists them. Only units a plant's tags commonly carry, in Latin
# and in Russian spelling; any other keeps its text with UnitId -1 (Part 8: not a UNECE unit).
_UNITS = (
    (("°C", "°С", "degC"), "CEL", "degree Celsius"), (("K",), "KEL", "kelvin"),
    (("°F",), "FAH", "degree Fahrenheit"), (("%",), "P1", "percent"),
    (("bar", "бар"), "BAR", "bar [unit of pressure]"), (("mbar", "мбар"), "MBR", "millibar"),
    (("Pa", "Па"), "PAL", "pascal"), (("kPa", "кПа"), "KPA", "kilopascal"),
    (("MPa", "МПа"), "MPA", "megapascal"), (("hPa", "гПа"), "A97", "hectopascal"),
    (("m3/h", "m³/h", "м3/ч", "м³/ч"), "MQH", "cubic metre per hour"),
    (("m3/s", "m³/s", "м3/с", "м³/с"), "MQS", "cubic metre per second"),
    (("l/min", "л/мин"), "L2", "litre per minute"), (("l/s", "л/с"), "G51", "litre per second"),
    (("t/h", "т/ч"), "E18", "tonne per hour"), (("kg/h", "кг/ч"), "E93", "kilogram per hour"),
    (("kg/s", "кг/с"), "KGS", "kilogram per second"), (("m3", "m³", "м3", "м³"), "MTQ", "cubic metre"),
    (("l", "л"), "LTR", "litre"), (("t", "т"), "TNE", "tonne (metric ton)"),
    (("kg", "кг"), "KGM", "kilogram"),
    (("A", "А"), "AMP", "ampere"), (("mA", "мА"), "4K", "milliampere"), (("V", "В"), "VLT", "volt"),
    (("mV", "мВ"), "2Z", "millivolt"), (("kV", "кВ"), "KVT", "kilovolt"), (("W", "Вт"), "WTT", "watt"),
    (("kW", "кВт"), "KWT", "kilowatt"), (("MW", "МВт"), "MAW", "megawatt"),
    (("kWh", "kW·h", "кВт·ч", "кВтч"), "KWH", "kilowatt hour"),
    (("MWh", "MW·h", "МВт·ч"), "MWH", "megawatt hour"),
    (("kVA", "kV·A", "кВА", "кВ·А"), "KVA", "kilovolt - ampere"), (("kvar", "квар"), "KVR", "kilovar"),
    (("Hz", "Гц"), "HTZ", "hertz"), (("rpm", "r/min", "об/мин"), "RPM", "revolutions per minute"),
    (("s", "с"), "SEC", "second [unit of time]"), (("ms", "мс"), "C26", "millisecond"),
    (("min", "мин"), "MIN", "minute [unit of time]"), (("h", "ч"), "HUR", "hour"),
    (("m", "м"), "MTR", "metre"), (("mm", "мм"), "MMT", "millimetre"), (("cm", "см"), "CMT", "centimetre"),
    (("m/s", "м/с"), "MTS", "metre per second"), (("mm/s", "мм/с"), "C16", "millimetre per second"),
    (("N", "Н"), "NEW", "newton"), (("kN", "кН"), "B47", "kilonewton"),
    (("N·m", "Nm", "Н·м"), "NU", "newton metre"),
    (("Ω", "Ом"), "OHM", "ohm"), (("lx", "лк"), "LUX", "lux"), (("dB", "дБ"), "2N", "decibel"),
    (("°",), "DD", "degree [unit of angle]"), (("pH",), "Q30", "pH (potential of Hydrogen)"),
)
UNITS: dict[str, tuple[str, str]] = {text: (code, name) for texts, code, name in _UNITS for text in texts}

# A bit tag's TrueState and FalseState where tags.csv names none: in the station's language.
STATES = {"ru": ("Вкл", "Выкл"), "en": ("On", "Off")}


def unit_id(code: str) -> int:
    """The UnitId of a UNECE common code: its (at most 3) ASCII characters as one integer, the
    first the most significant byte (OPC UA Part 8 5.6.3: "CEL" -> 4408652)."""
    n = 0
    for c in code:
        n = n << 8 | ord(c)
    return n


def eu_information(unit: str) -> ua.EUInformation:
    text = unit.strip()
    code, name = UNITS.get(text, ("", text))
    return ua.EUInformation(NamespaceUri=UNECE_UNITS, UnitId=unit_id(code) if code else -1,
                            DisplayName=ua.LocalizedText(text), Description=ua.LocalizedText(name))


def variant_type(tag: Tag) -> ua.VariantType:
    """The DataType of a tag's variable: what a client reads and must send."""
    if tag.scaling is not None:
        return ua.VariantType.Double
    return {TagType.BIT: ua.VariantType.Boolean, TagType.WORD: ua.VariantType.UInt16,
            TagType.INT16: ua.VariantType.Int16, TagType.BCD: ua.VariantType.UInt16,
            TagType.INT32: ua.VariantType.Int32, TagType.FLOAT32: ua.VariantType.Float}[tag.type]


def python(kind: ua.VariantType) -> Callable[[float], Any]:
    """The Python type asyncua encodes as `kind`, from a physical value (a float)."""
    if kind is ua.VariantType.Boolean:
        return bool
    if kind in (ua.VariantType.Double, ua.VariantType.Float):
        return float
    return int


@dataclass(frozen=True)
class TagNode:
    """How one tag's variable is made: its NodeId, DataType, AccessLevel and Historizing."""

    tag: Tag
    nodeid: ua.NodeId
    kind: ua.VariantType
    access: int  # READ, WRITE, HISTORY_READ bits
    historizing: bool = False


def tag_items(node: TagNode, parent: ua.NodeId,
              language: str = "") -> tuple[ua.AddNodesItem, list[ua.AddNodesItem]]:
    """The AddNodesItems of a tag's variable (under `parent`) and of its type's properties."""
    tag, idx = node.tag, node.nodeid.NamespaceIndex
    bit = tag.type is TagType.BIT
    variable = _variable(node.nodeid, parent, ua.QualifiedName(tag.name, idx), ua.ObjectIds.HasComponent,
                         ua.ObjectIds.TwoStateDiscreteType if bit else ua.ObjectIds.AnalogItemType,
                         ua.Variant(python(node.kind)(0), node.kind), ua.NodeId(node.kind.value),
                         node.access, node.historizing, tag.description)
    properties: list[tuple[str, Any, int]] = []
    if bit:
        on, off = STATES.get(language, STATES["en"])
        locale = language if language in STATES else "en"
        properties += [("TrueState", ua.LocalizedText(on, locale), ua.ObjectIds.LocalizedText),
                       ("FalseState", ua.LocalizedText(off, locale), ua.ObjectIds.LocalizedText)]
    else:
        lo, hi = write_range(tag)  # PhyMin..PhyMax: what a client may write
        properties.append(("EURange", ua.Range(Low=lo, High=hi), ua.ObjectIds.Range))
        if tag.scaling is not None:
            raw = sorted((tag.scaling.AppMin, tag.scaling.AppMax))
            properties.append(("InstrumentRange", ua.Range(Low=raw[0], High=raw[1]), ua.ObjectIds.Range))
        if tag.unit.strip():
            properties.append(("EngineeringUnits", eu_information(tag.unit), ua.ObjectIds.EUInformation))
    children = [_variable(ua.NodeId(f"{node.nodeid.Identifier}.{name}", idx), node.nodeid,
                          ua.QualifiedName(name, 0), ua.ObjectIds.HasProperty, ua.ObjectIds.PropertyType,
                          ua.Variant(value), ua.NodeId(datatype), READ)
                for name, value, datatype in properties]
    return variable, children


def _variable(nodeid: ua.NodeId, parent: ua.NodeId, name: ua.QualifiedName, reference: int, typedef: int,
              value: ua.Variant, datatype: ua.NodeId, access: int, historizing: bool = False,
              description: str = "") -> ua.AddNodesItem:
    """A Variable node as asyncua's own `create_variable` makes one, with its TypeDefinition."""
    attrs = ua.VariableAttributes()
    attrs.DisplayName = ua.LocalizedText(name.Name)
    attrs.Description = ua.LocalizedText(description or name.Name)
    attrs.DataType = datatype
    attrs.Value = value
    attrs.ValueRank = ua.ValueRank.Scalar
    attrs.ArrayDimensions = None
    attrs.WriteMask = attrs.UserWriteMask = 0
    attrs.Historizing = historizing
    attrs.AccessLevel = attrs.UserAccessLevel = access
    item = ua.AddNodesItem()
    item.RequestedNewNodeId = nodeid
    item.BrowseName = name
    item.NodeClass = ua.NodeClass.Variable
    item.ParentNodeId = parent
    item.ReferenceTypeId = ua.NodeId(reference)
    item.TypeDefinition = ua.NodeId(typedef)
    item.NodeAttributes = attrs
    return item


@dataclass(frozen=True)
class BuildInfo:
    """Server/ServerStatus/BuildInfo (Part 5): this program, from its package's metadata."""

    product_uri: str
    manufacturer: str
    product: str
    version: str
    build_number: str
    build_date: datetime


def build_info() -> BuildInfo:
    """The installed package's version; its build date is when its metadata was written (the
    install). From a source tree that was never installed: version 0, built now."""
    try:
        dist = importlib.metadata.distribution(DISTRIBUTION)
    except importlib.metadata.PackageNotFoundError:
        logger.warning("package %s is not installed: BuildInfo names version 0", DISTRIBUTION)
        return BuildInfo(PRODUCT_URI, PRODUCT, PRODUCT, "0", "0", datetime.now(UTC))
    meta = dist.metadata
    manufacturer = meta.get("Author") or meta.get("Maintainer") or PRODUCT
    files = [Path(str(dist.locate_file(f))) for f in dist.files or () if f.name == "METADATA"]
    built = datetime.fromtimestamp(files[0].stat().st_mtime, UTC) if files and files[0].exists() else \
        datetime.now(UTC)
    return BuildInfo(PRODUCT_URI, manufacturer, PRODUCT, dist.version, dist.version, built)
