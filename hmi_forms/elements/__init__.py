"""Qt-free element models, one per element type of the manual's section 2.4.3."""

from hmi_forms.elements.analog import AnalogBase, AnalogOutput
from hmi_forms.elements.base import Element
from hmi_forms.elements.discrete import (
    DiscreteAnimation,
    DiscreteBase,
    DiscreteColorLabel,
    DiscreteControlledEnable,
)
from hmi_forms.elements.graph import Graph
from hmi_forms.elements.journal import MessageJournal
from hmi_forms.elements.static import DateTime, StaticPicture, StaticText
from hmi_forms.elements.sync import SyncGenerator, SyncTimer

ELEMENT_TYPES: dict[str, type[Element]] = {
    cls.TYPE: cls
    for cls in (
        SyncGenerator, SyncTimer, DiscreteBase, DiscreteColorLabel, DiscreteControlledEnable,
        DiscreteAnimation, AnalogBase, AnalogOutput, StaticPicture, StaticText, Graph,
        MessageJournal, DateTime,
    )
}

__all__ = ["ELEMENT_TYPES", "Element"]
