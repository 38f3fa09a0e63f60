"""The console's language: Russian or English, with Qt's own translation mechanism.

`console_ru.ts` (in this folder, kept in the repository, edited with Qt Linguist or by hand) is
compiled to `console_ru.qm` by the build (`make translations`, run by `make run`, `make test` and
`make dist`, whose wheel carries the .qm) with the `lrelease` that PySide6-Essentials ships; a
checkout run without make compiles it on first use the same way. English is the source text.
Qt's own strings (Yes/No, Cancel) come from the qtbase catalogue PySide6 ships. Form texts stay
as the engineer wrote them.
"""

from __future__ import annotations

import logging
import subprocess
from pathlib import Path

import PySide6
from PySide6.QtCore import QCoreApplication, QLibraryInfo, QLocale, QTranslator

from hmi_forms.elements import formats
from hmi_forms.widgets.base import SHARED_LAYERS

logger = logging.getLogger(__name__)
HERE = Path(__file__).resolve().parent
LRELEASE = Path(PySide6.__file__).parent / "lrelease"


def system_language() -> str:
    return "ru" if QLocale.system().language() == QLocale.Language.Russian else "en"


def compiled(language: str) -> Path | None:
    """The .qm of a language, compiled from its .ts when missing or older (an installed package
    holds the .qm alone, compiled when its wheel was built); None when there is no catalogue for
    it (English is the source text) or lrelease fails."""
    ts = HERE / f"console_{language}.ts"
    qm = ts.with_suffix(".qm")
    if not ts.exists():
        return qm if qm.exists() else None
    if not qm.exists() or qm.stat().st_mtime < ts.stat().st_mtime:
        try:
            subprocess.run([str(LRELEASE), "-silent", str(ts), "-qm", str(qm)], check=True, timeout=60)
        except (OSError, subprocess.SubprocessError) as e:  # the console shows its English source text
            logger.warning("console language %s not compiled (%s): %s", language, LRELEASE, e)
            return None
    return qm


def install(app: QCoreApplication, language: str = "") -> str:
    """Translate the console into `language` ("" follows the system locale); returns the language
    used. Translators installed before are replaced, so a second call switches languages."""
    language = language if language in ("ru", "en") else system_language()
    uninstall(app)
    formats.set_language(language)
    if language == "en":
        return language
    qtbase = Path(QLibraryInfo.path(QLibraryInfo.LibraryPath.TranslationsPath)) / f"qtbase_{language}.qm"
    for path in (compiled(language), qtbase):
        translator = QTranslator(app)
        if path is not None and translator.load(str(path)):
            app.installTranslator(translator)
    return language


def uninstall(app: QCoreApplication) -> None:
    """Back to the source texts and the default formats; the form elements' shared pictures, which
    hold their words ("period", "disabled"), are drawn again in the next language."""
    for old in app.findChildren(QTranslator):
        app.removeTranslator(old)
        old.deleteLater()
    formats.set_language("")
    SHARED_LAYERS.clear()
