"""The one records model behind the form's journal, the workstation's dock and the viewer."""

from PySide6.QtCore import Qt

from hmi_forms.widgets.journal import PALETTE
from hmi_forms.widgets.records import JOURNAL_COLUMNS, RecordsModel, records_view
from registrar.query import Row

ROWS = [
    Row(3, 1_700_000_000.25, "operator", None, None, "ivanov", 0o4030, 7.0, "Уставка"),
    Row(2, 1_700_000_000.0, "message", 1, 2, None, 3, None, None),
    Row(1, 1_700_000_000.0, "data", 1, 1, "04010", None, 12.5, None),
]


def cells(model: RecordsModel, role=Qt.ItemDataRole.DisplayRole) -> list[list]:
    return [[model.index(r, c).data(role) for c in range(model.columnCount())]
            for r in range(model.rowCount())]


def test_archive_columns_name_types_of_messages_and_addresses_of_writes(qtbot):
    model = RecordsModel()
    model.set_rows(ROWS)
    rows = cells(model)
    assert [r[1:] for r in rows] == [
        ["operator", "", "", "ivanov", "04030", "7", "Уставка"],
        ["message", "1", "alarm", "", "3", "", ""],
        ["data", "1", "1", "04010", "", "12.500", ""],
    ]
    assert rows[0][0].endswith(".250")
    back = [c[0] for c in cells(model, Qt.ItemDataRole.BackgroundRole)]
    fore = [c[0] for c in cells(model, Qt.ItemDataRole.ForegroundRole)]
    assert back[0] is None and back[1] is not None and back[2] is None
    assert fore[0] is not None and fore[2] is None  # operator actions stand out, data does not


def test_form_journal_names_a_textless_message_by_number_and_keeps_the_view_on_equal_rows(qtbot):
    model = RecordsModel(JOURNAL_COLUMNS, PALETTE)
    view = records_view(model, row_height=20)
    qtbot.addWidget(view)
    model.set_rows(ROWS)
    assert [model.headerData(c, Qt.Orientation.Horizontal) for c in range(7)] == [
        "Time", "Kind", "Group", "Type", "Source", "Text", "Value"]
    assert model.index(1, 5).data() == "message 3"
    assert model.index(1, 2).data(Qt.ItemDataRole.ForegroundRole) == PALETTE.fore[2]
    resets = []
    model.modelReset.connect(lambda: resets.append(1))
    model.set_rows(list(ROWS))
    assert resets == []  # same rows: selection and scroll position survive a refresh
    model.set_rows(ROWS[:1])
    assert resets == [1] and model.rowCount() == 1
