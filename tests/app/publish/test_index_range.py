"""What a monitored item keeps of the values it sampled (index_range.Sampled): asyncua deep-copies
each one lest the server change it in place; a value that cannot change in place is kept as it is."""

from __future__ import annotations

from asyncua import ua

from app.publish.index_range import Sampled


def test_a_sampled_value_that_cannot_change_in_place_is_kept_a_list_is_copied() -> None:
    kept = Sampled()
    word = ua.DataValue(ua.Variant(b"\x01\x02", ua.VariantType.ByteString))
    tick = ua.DataValue(ua.Variant(7, ua.VariantType.UInt64))
    kept.set_current_datavalue(word)
    kept.set_current_datavalue(tick)
    assert kept.get_old_datavalue() is word and kept.get_current_datavalue() is tick
    names = ["a", "b"]
    kept.set_current_datavalue(ua.DataValue(ua.Variant(names, ua.VariantType.String)))
    names.append("c")  # changed in place after it was sampled: the item still holds what it sampled
    current = kept.get_current_datavalue()
    assert current is not None and current.Value is not None and current.Value.Value == ["a", "b"]
