"""The words of the Qt-free layers in the station's `Language`: alarm texts, their transitions,
why NetPlc is not running, the station's 'system' records. These layers cannot use Qt's tr(),
and their texts are built once, on the engine thread, then travel as they are to the journal,
OPC UA, MQTT and every console; so they are built in the station's language from this
catalogue, never translated after. Alarm identities (LEVEL.HH) and journal kinds are keys, not
prose, and stay as they are. The log stays English (ENGLISH), for whoever supports the station.
A sentence made of parts (a pair's record naming the cause of a takeover) takes its parts as
`Phrase`s, said in the sentence's language. netplc cannot import this catalogue: its exchange's
words are its own (netplc/exchange.py LINK_WORDS), in English, and said here in Russian."""

from __future__ import annotations

import os
from collections.abc import Mapping
from dataclasses import dataclass, field

from netplc.exchange import LINK_WORDS

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
        **LINK_WORDS,
        # a hot-standby pair's records (app/station/pair.py) and the causes they name
        "role starting": "starting", "role primary": "primary", "role standby": "standby",
        "pair role": "pair {letter}: {old} -> {new}: {cause}",
        "pair stays": "pair {letter}: stays {role} ({cause}): the arbiter decides: {error}",
        "pair link lost": "pair {letter}: link to the partner lost ({role}): {error}",
        "pair refused": "pair {letter}: partner refused: {why}",
        "pair handover": "pair {letter}: primary -> standby: {cause}",
        "same letter": "the partner is {letter} as well",
        "station differs": "the partner's station differs: {files}",
        "no partner": "no partner answered within {ms:.0f} ms of the start",
        "partner is": "partner {letter} is {role}",
        "lease held": "{cause}; the partner holds the arbiter's lease",
        "handed over": "handed over by the partner: {cause}",
        "lost both": "lost the arbiter ({error}) and the partner",
        "partner silent": "partner silent for {ms:.0f} ms",
        "taken over": "the partner took over from scan {scan} (it heard nothing for {ms:.0f} ms); {dropped} "
                      "records of the later scans are the partner's to make",
        "into standby": "IntoStandBy by {user}",
        "primary stopping": "the primary is stopping",
        "link closed": "the partner closed the pair link",
        "retained current": "current", "retained previous": "previous", "retained zeroes": "zeroes",
        # `main.py check` (app/station/check.py, what app/station/load.py found good) and the CLI
        "note station": "station {path}",
        "note program": "program {file}: {instrs} instructions, {words} words",
        "note simulator": "node {node} simulator program {program}: {instrs} instructions",
        "note messages": "messages {file}: {n} texts",
        "note tags": "tags {file}: {n} tags, {alarms} with alarms",
        "note users": "users {file}: {n}",
        "note users default": "users {file}: {n}, {name!r} at the workstation until someone logs in",
        "note forms": "forms in {folder}: {n} loaded",
        "note pair": "pair: {ours} and {theirs} hold the same station",
        "check split brain": '{path}: redundancy.arbiter: "none": when the link between the pair breaks '
                             "while both run, both act as primary (split brain)",
        "check horn": "{path}: alarm_horn: {bit} is written by the program (line {line}: {text}): the "
                      "station sets this bit, the program may only read it",
        "check no pair": "{path}: [redundancy] missing: not one of a pair",
        "check same letter": "{path}: redundancy.letter: both stations are {letter}: one must be A, the "
                             "other B",
        "check differ": "{ours} and {theirs} are not the same station: {files} differ",
        "ok": "ok: {text}", "warning": "warning: {text}", "problems found": "{n} problem(s) found",
        "no redundancy": "{target}: no [redundancy] in its station.toml",
        "no pair answer": "{address}: no answer from the station's pair link: {error}",
        "status letter": "letter", "status role": "role", "status partner": "partner", "status link": "link",
        "status last_takeover": "last takeover", "status lag": "lag", "status switchovers": "switchovers",
        "link is up": "up", "link is down": "DOWN",
        "user added": "user {user} added as {role}", "user removed": "user {user} removed",
        "password changed": "password of {user} changed",
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
        "link up": "узел {node} ({endpoint}): связь есть",
        "link down": "узел {node} ({endpoint}): связи нет",
        "link down because": "узел {node} ({endpoint}): связи нет: {error}",
        "role starting": "запуск", "role primary": "основная", "role standby": "резервная",
        "pair role": "пара, станция {letter}: {old} -> {new}: {cause}",
        "pair stays": "пара, станция {letter}: остаётся в роли «{role}» ({cause}): решает арбитр: {error}",
        "pair link lost": "пара, станция {letter}: связь с партнёром потеряна (роль «{role}»): {error}",
        "pair refused": "пара, станция {letter}: партнёр отвергнут: {why}",
        "pair handover": "пара, станция {letter}: основная -> резервная: {cause}",
        "same letter": "партнёр тоже {letter}",
        "station differs": "станция партнёра другая: различаются {files}",
        "no partner": "партнёр не ответил за {ms:.0f} мс от запуска",
        "partner is": "партнёр {letter}: {role}",
        "lease held": "{cause}; аренда арбитра у партнёра",
        "handed over": "передано партнёром: {cause}",
        "lost both": "потеряны арбитр ({error}) и партнёр",
        "partner silent": "партнёр молчит {ms:.0f} мс",
        "taken over": "партнёр взял управление со скана {scan} (не слышал эту станцию {ms:.0f} мс); записи "
                      "последующих сканов, {dropped}, сделает партнёр",
        "into standby": "IntoStandBy: {user}",
        "primary stopping": "основная останавливается",
        "link closed": "партнёр закрыл связь пары",
        "retained current": "текущего сохранения", "retained previous": "предыдущего сохранения",
        "retained zeroes": "нулей",
        "note station": "станция {path}",
        "note program": "программа {file}: инструкций {instrs}, слов {words}",
        "note simulator": "программа имитатора узла {node} {program}: инструкций {instrs}",
        "note messages": "сообщения {file}: текстов {n}",
        "note tags": "теги {file}: тегов {n}, с авариями {alarms}",
        "note users": "пользователи {file}: {n}",
        "note users default": "пользователи {file}: {n}, {name!r} за рабочим местом, пока никто не вошёл",
        "note forms": "мнемосхемы в {folder}: загружено {n}",
        "note pair": "пара: в {ours} и {theirs} одна и та же станция",
        "check split brain": '{path}: redundancy.arbiter: "none": если связь между станциями пары '
                             "прервётся, когда обе работают, обе станут основными (split brain)",
        "check horn": "{path}: alarm_horn: бит {bit} пишет программа (строка {line}: {text}): этот бит "
                      "ставит станция, программа может только читать его",
        "check no pair": "{path}: нет [redundancy]: станция не входит в пару",
        "check same letter": "{path}: redundancy.letter: обе станции — {letter}: одна должна быть A, "
                             "другая B",
        "check differ": "{ours} и {theirs} — не одна и та же станция: различаются {files}",
        "ok": "норма: {text}", "warning": "предупреждение: {text}",
        "problems found": "найдено проблем: {n}",
        "no redundancy": "{target}: в его station.toml нет [redundancy]",
        "no pair answer": "{address}: связь пары станции не отвечает: {error}",
        "status letter": "буква", "status role": "роль", "status partner": "партнёр", "status link": "связь",
        "status last_takeover": "последний переход", "status lag": "отставание",
        "status switchovers": "переключений",
        "link is up": "есть", "link is down": "НЕТ",
        "user added": "пользователь {user} добавлен, роль {role}",
        "user removed": "пользователь {user} удалён",
        "password changed": "пароль пользователя {user} изменён",
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
class Phrase:
    """A part of a sentence, said in the sentence's language when the sentence is said."""

    name: str
    values: Mapping[str, object] = field(default_factory=dict)


def phrase(name: str, /, **values: object) -> Phrase:
    return Phrase(name, values)


@dataclass(frozen=True)
class Words:
    """The catalogue of one language: `words("limit", label=..., ...)` is its text, filled in."""

    language: str

    def __call__(self, name: str, /, **values: object) -> str:
        return TEXTS[self.language][name].format(**{k: self.say(v) for k, v in values.items()})

    def say(self, value: object) -> object:
        """A value as it goes into a sentence: a phrase said in this language, the rest as it is."""
        return self(value.name, **value.values) if isinstance(value, Phrase) else value

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
