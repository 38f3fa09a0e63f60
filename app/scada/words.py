"""The words of the Qt-free layers in the station's `Language`: alarm texts, their transitions,
why NetPlc is not running, the station's 'system' records. These layers cannot use Qt's tr(),
and their texts are built once, on the engine thread, then travel as they are to the journal,
OPC UA, MQTT and every console; so they are built in the station's language from this
catalogue, never translated after. Alarm identities (LEVEL.HH) and journal kinds are keys, not
prose, and stay as they are. The log stays English (ENGLISH), for whoever supports the station."""

from __future__ import annotations

import os
from dataclasses import dataclass

TEXTS: dict[str, dict[str, str]] = {
    "en": {
        "HH": "high-high", "H": "high", "L": "low", "LL": "low-low",
        "limit": "{label}: {word} ({key} {limit})",
        "bad quality": "{label}: bad quality",
        "not running": "NetPlc is not running",
        "no standby": "No standby: the pair runs on one station",
        "normal": "normal", "active-unacknowledged": "active-unacknowledged",
        "active-acknowledged": "active-acknowledged", "returned-unacknowledged": "returned-unacknowledged",
        "shelved": "shelved", "suppressed": "suppressed", "out-of-service": "out-of-service",
        "not a number": "not a number", "raw": "raw", "by": "by {user}",
        "acknowledged": "acknowledged", "reset": "reset", "comment": "comment: {text}",
        "unshelved": "unshelved", "suppressed by design": "suppressed by design",
        "suppression ended": "suppression ended", "shelving ran out": "shelving by {user} ran out",
        "one-shot ended": "one-shot shelving by {user} ended: returned to normal",
        "shelved once": "shelved once, until it returns to normal (at most until {stamp})",
        "shelved for": "shelved for {duration:g} s until {stamp}",
        "taken out of service": "taken out of service", "returned to service": "returned to service",
        "halted": "halted by HLT",
        "emergency stop": "emergency stop by bit {bit} (code {code})",
        "stopped by": "stopped by {user} (code 0)",
        "stopped": "stopped by the operator or the watchdog (code 0)",
        # the station's 'system' records (app/station/runtime.py)
        "cannot start": "station cannot start: {problem}",
        "starting": "station starting: {path}",
        "form not loaded": "form not loaded: {problem}",
        "forms loaded": "forms loaded: {forms}, of their elements {elements} act on the station (sync "
                        "generators, RegData/RegMessages), with or without a window",
        "program loaded": "program loaded: {source} ({instrs} instructions, {words} words)",
        "started": "station started: NetSyncTime {sync} ms, retentive memory from {restored}",
        "forces restored": "{n} retained forces restored from {file} (RetainForces = true)",
        "forces not saved": "retained forces not saved: {file}: {error}",
        "stays down": "{text}; the node stays down until it does",
        "station stopped": "station stopped",
        "node answers": "simulated node {node} answers again",
        "node silent": "simulated node {node} stopped answering",
    },
    "ru": {
        "HH": "верхний аварийный", "H": "верхний предупредительный", "L": "нижний предупредительный",
        "LL": "нижний аварийный",
        "limit": "{label}: {word} ({key} {limit})",
        "bad quality": "{label}: недостоверное значение",
        "not running": "NetPlc не работает",
        "no standby": "Нет резерва: пара работает на одной станции",
        "normal": "норма", "active-unacknowledged": "активна, не квитирована",
        "active-acknowledged": "активна, квитирована", "returned-unacknowledged": "ушла, не квитирована",
        "shelved": "отложена", "suppressed": "подавлена", "out-of-service": "выведена из работы",
        "not a number": "не число", "raw": "код", "by": "оператор {user}",
        "acknowledged": "квитирована", "reset": "сброшена", "comment": "комментарий: {text}",
        "unshelved": "возвращена из отложенных", "suppressed by design": "подавлена по проекту",
        "suppression ended": "подавление снято", "shelving ran out": "срок откладывания ({user}) истёк",
        "one-shot ended": "разовое откладывание ({user}) окончено: вернулась в норму",
        "shelved once": "отложена до возврата в норму (не дольше чем до {stamp})",
        "shelved for": "отложена на {duration:g} с до {stamp}",
        "taken out of service": "выведена из работы", "returned to service": "введена в работу",
        "halted": "остановлена командой HLT",
        "emergency stop": "аварийный останов битом {bit} (код {code})",
        "stopped by": "остановлена: {user} (код 0)",
        "stopped": "остановлена оператором или сторожевым таймером (код 0)",
        "cannot start": "станция не может запуститься: {problem}",
        "starting": "станция запускается: {path}",
        "form not loaded": "мнемосхема не загружена: {problem}",
        "forms loaded": "мнемосхемы загружены: {forms}, из их элементов {elements} действуют на станции "
                        "(генераторы синхронизации, RegData/RegMessages), с окном и без",
        "program loaded": "программа загружена: {source} (инструкций: {instrs}, слов: {words})",
        "started": "станция запущена: NetSyncTime {sync} мс, сохраняемая память из {restored}",
        "forces restored": "восстановлено сохранённых фиксаций: {n}, из {file} (RetainForces = true)",
        "forces not saved": "сохранённые фиксации не записаны: {file}: {error}",
        "stays down": "{text}; узел считается отключённым, пока имя не разрешится",
        "station stopped": "станция остановлена",
        "node answers": "имитируемый узел {node} снова отвечает",
        "node silent": "имитируемый узел {node} перестал отвечать",
    },
}


def system_language() -> str:
    """The language of the system locale, as the console's own default (app/gui/i18n) chooses it."""
    for name in ("LC_ALL", "LC_MESSAGES", "LANG"):
        value = os.environ.get(name, "")
        if value:
            return "ru" if value.lower().startswith("ru") else "en"
    return "en"


@dataclass(frozen=True)
class Words:
    """The catalogue of one language: `words("limit", label=..., ...)` is its text, filled in."""

    language: str

    def __call__(self, name: str, /, **values: object) -> str:
        return TEXTS[self.language][name].format(**values)

    @property
    def stamp(self) -> str:
        """The strftime format of a date and time in this language, the console's (imported when
        asked: a headless station loads no form code, tests/test_boundaries.py)."""
        from hmi_forms.elements.formats import DATES, TIME

        return f"{DATES[self.language]} {TIME}"


def words(language: str = "") -> Words:
    """The station's `Language` ("" follows the system locale)."""
    return Words(language if language in TEXTS else system_language())


ENGLISH = Words("en")  # of the log, read by whoever supports the station
