"""Command line of the station (placeholder until the application issue lands: a window saying so)."""

from __future__ import annotations

import sys


def main(argv: list[str] | None = None) -> int:
    from PySide6.QtWidgets import QApplication, QLabel

    app = QApplication(sys.argv if argv is None else ["netplc-station", *argv])
    label = QLabel("NetPlc Station: the operator workstation is not built yet (application issue).")
    label.resize(520, 80)
    label.show()
    return app.exec()
