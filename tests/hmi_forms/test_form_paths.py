"""Files a form names stay inside the station: one outside (`/etc/passwd`, `../../x.png`) is a named
problem, and the form opens with the element shown without it, unless the station allows it."""

from __future__ import annotations

import shutil
from pathlib import Path

from hmi_forms.form import load_form, load_forms
from hmi_forms.widgets.form_view import FormView
from netplc.engine import Engine, FakeClock
from netplc.program import parse
from tests.hmi_forms.helpers import engine_target, write_form
from tests.hmi_forms.test_widgets import EXAMPLE

PICTURE = {"type": "StaticPicture", "Name": "Pic", "x": 0, "y": 0, "w": 50, "h": 50}
LAMP = {"type": "DiscreteBase", "Name": "Lamp", "x": 60, "y": 0, "w": 50, "h": 50, "InAddr": "02000",
        "ImageFalse": 0, "ImageTrue": 1}


def station(tmp_path: Path) -> tuple[Path, Path]:
    """A station folder with forms/ and images/, and a picture outside it (tmp_path/outside.png)."""
    st = tmp_path / "plant" / "station"
    (st / "forms").mkdir(parents=True)
    (st / "images").mkdir()
    for where in (st / "images" / "on.png", st / "forms" / "off.png", tmp_path / "outside.png"):
        shutil.copy(EXAMPLE / "forms" / "images" / "pump_off.png", where)
    return st, st / "forms"


def test_files_outside_the_station_are_named_and_left_out(tmp_path: Path) -> None:
    st, forms = station(tmp_path)
    write_form(forms, [{**PICTURE, "Image": "/etc/passwd"},
                       {**PICTURE, "Name": "Up", "Image": "../../../outside.png"},
                       {**PICTURE, "Name": "Ok", "Image": "../images/on.png"}, LAMP],
               images=["off.png", "/etc/passwd"], form={"title": "t", "width": 800, "height": 600,
                                                        "BackgroundImage": "../../../outside.png"})
    loaded, problems = load_forms(forms, station=st)
    path = forms / "t.hmi"
    assert [f.path for f in loaded] == [path]
    form = loaded[0]
    assert problems == form.problems
    assert [p.split(": ", 3)[1:3] for p in problems] == [
        ["form", "BackgroundImage"],
        ["image #1", f'image file "/etc/passwd" is outside the station folder {forms} and {st} (shown '
                     "without it; allow_outside = true in station.toml allows it)"],
        ['element "Pic"', "Image"], ['element "Up"', "Image"]]
    assert all(p.startswith(f"{path}: ") and "outside the station folder" in p for p in problems)
    assert form.BackgroundImage is None and form.images == [(forms / "off.png").resolve(), None]
    pictures = {el.Name: el for el in form.elements}
    assert set(pictures) == {"Pic", "Up", "Ok", "Lamp"}
    assert pictures["Pic"].Image is None and pictures["Up"].Image is None
    assert pictures["Ok"].Image == (st / "images" / "on.png").resolve()


def test_the_form_with_a_left_out_file_still_renders(tmp_path: Path, qtbot) -> None:
    st, forms = station(tmp_path)
    write_form(forms, [{**PICTURE, "Image": "/etc/passwd"}, LAMP], images=["off.png", "/etc/passwd"])
    form = load_form(forms / "t.hmi", station=st)
    engine = Engine(parse(""), clock=FakeClock(), wallclock=lambda: 0.0)
    view = FormView(form, engine_target(engine))
    qtbot.addWidget(view)
    engine.mem.set_bit(0o2000, 1)
    engine.scan()
    view.refresh(engine.snapshot)
    view.flush()
    assert not view.grab().isNull()


def test_without_a_station_folder_the_form_folder_is_the_limit(tmp_path: Path) -> None:
    _, forms = station(tmp_path)
    write_form(forms, [{**PICTURE, "Image": "../images/on.png"}])
    assert load_form(forms / "t.hmi").problems == [
        f'{forms / "t.hmi"}: element "Pic": Image: image file "../images/on.png" is outside the station '
        f"folder {forms} (shown without it; allow_outside = true in station.toml allows it)"]


def test_a_station_that_allows_outside_files_gets_them(tmp_path: Path) -> None:
    st, forms = station(tmp_path)
    write_form(forms, [{**PICTURE, "Image": str(tmp_path / "outside.png")}])
    form = load_form(forms / "t.hmi", station=st, allow_outside=True)
    assert form.problems == [] and form.elements[0].Image == (tmp_path / "outside.png").resolve()


def test_a_link_inside_pointing_outside_is_outside(tmp_path: Path) -> None:
    st, forms = station(tmp_path)
    (forms / "link.png").symlink_to(tmp_path / "outside.png")
    write_form(forms, [{**PICTURE, "Image": "link.png"}])
    form = load_form(forms / "t.hmi", station=st)
    assert form.elements[0].Image is None and "outside the station folder" in form.problems[0]
