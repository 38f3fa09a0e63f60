"""The operator workstation and the offline viewer (the only Qt code of app/)."""

from app.gui.pyside_guard import make_singletons_immortal

make_singletons_immortal()
