"""The words of the Qt-free layers in the station's `Language`: alarm texts, their transitions,
why NetPlc is not running, the station's 'system' records. These layers cannot use Qt's tr(),
and their texts are built once, on the engine thread, then travel as they are to the journal,
OPC UA, MQTT and every console; so they are built in the station's language from this
catalogue, never translated after. Alarm identities (LEVEL.HH) and journal kinds are keys, not
prose, and stay as they are. The log stays English (ENGLISH), for whoever supports the station.
A sentence made of parts (a pair's record naming the cause of a takeover) takes its parts as
`Phrase`s, said in the sentence's language. netplc cannot import this catalogue: its records
(the exchange's links, the operator's writes and forces, the engine's faults) are its own
(netplc/words.py WORDS), in English, and said here in Russian; the runtime hands the engine and the
exchange this catalogue to say them."""

from __future__ import annotations

import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from netplc.words import WORDS as NETPLC_WORDS
from netplc.words import Phrase as Phrase
from netplc.words import WordedError
from netplc.words import phrase as phrase

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
        "user no name": "a user needs a name",
        "user exists": "user {name!r} exists already (passwd changes the password)",
        "no user": "no user {name!r}", "no such role": "role {role!r} is not one of {roles}",
        "empty password": "the password is empty", "passwords differ": "the two passwords differ",
        "password changed": "password of {user} changed",
        **NETPLC_WORDS,
        # the station's problems and its servers' starts (app/station/runtime.py, app/publish/station.py)
        "modbus not started": "Modbus server not started: {path}: modbus_server.port: cannot listen on "
                              "{host}:{port}: {error}",
        "modbus not yet": "Modbus server not started yet: {path}: modbus_server.port: {fault}; retrying "
                          "every {every:g} s",
        "force not restored": "retained force not restored: {problem}",
        "scan failed": "scan failed: {error}",
        "opcua not started": "OPC UA server not started: {path}: opcua.endpoint: {error}",
        "opcua started": "OPC UA server at {endpoint} ({security}), {tags} tags",
        "opcua secure": "Basic256Sha256 Sign&Encrypt, trusted clients", "opcua open": "no security, loopback",
        "mqtt started": "MQTT Sparkplug B publisher to {broker} as {node}, {tags} metrics, devices {devices}",
        "mqtt primary": "MQTT Sparkplug B publisher to {broker} as {node}, {tags} metrics, devices "
                        "{devices}, primary host {host}",
        "no devices": "none",
        "logged in": "logged in as {role}", "logged out": "logged out", "logged out idle": "logged out: idle",
        "logged out switched": "logged out: user switched",
        "joining": "the station is joining its pair",
        "pair starting": "the station is starting as one of a pair: it takes commands once it is the primary",
        "pair standby": "this station ({letter}) is the standby: the primary is {primary}",
        "nothing to hand over": "no standby on the pair link to hand over to",
        "pair link down": "pair link to {partner} down",
        # the command layer (app/authority/layer.py): its records, refusals and answers
        "refused": "refused {what}: {why}", "refused more": "refused {what}: {why} ({n} more refused like "
                                                              "it in the minute before)",
        # the policy's actions (app/authority/policy.py Action), as a refusal names them
        "action write": "write", "action acknowledge": "acknowledge", "action shelve": "shelve",
        "action unshelve": "unshelve", "action comment": "comment", "action silence": "silence",
        "action out of service": "out of service", "action force": "force", "action unforce": "unforce",
        "action run": "run", "action stop": "stop", "action step": "step", "action quit": "quit",
        "action users": "users", "action trust": "trust", "action IntoStandBy": "IntoStandBy",
        "action log in": "log in", "action open a session": "open a session",
        "login waits": "{n} failed logins from {host}: refused for {wait:.0f} s more",
        "login wrong": "wrong user name or password",
        "login wrong wait": "wrong user name or password; the next attempts wait {wait:g} s",
        "sessions full": "[opcua] max_consoles = {n} sessions are open already",
        "role viewer": "viewer", "role operator": "operator", "role engineer": "engineer",
        "role admin": "admin",
        "denied source": "needs the {role} role; clients with no user act as {has}",
        "denied nobody": "nobody is logged in ({role} needed)",
        "denied gone": "{user} is no longer a user ({role} needed)",
        "denied role": "needs the {role} role; {user} is {has}",
        "no tag": "no tag {name!r}", "no number": "{value!r} is not a number",
        "not writable point": "not among the points {section} writable names",
        "not whole": "{value!r} is not whole", "outside g": "{value} is outside {lo:g} .. {hi:g}",
        "alarm id string": "an alarm's identity is a String",
        "shelve args": "Shelve takes a String reason and a number of seconds",
        "tag name string": "a tag's name is a String",
        "session none": "security None at {endpoint} is for discovery only (GetEndpoints): sessions need "
                        "Basic256Sha256 Sign&Encrypt",
        "only tags": "only tags are written over OPC UA", "no node": "no such node",
        "only value": "only the value of a tag is written, not its {attribute}",
        "no device": "no such device of {node}", "not sparkplug": "not a Sparkplug B payload ({error})",
        "link metric": "a link metric, read-only", "no metric": "no such metric of {node}",
        "not 0 or 1": "{value!r} is not 0 or 1", "outside": "{value!r} is outside {lo} .. {hi}",
        "not applied": "{what}: not applied (see the journal)",
        "journal full": "the archive cannot take the record (disk full or too slow): not done",
        "busy": "the station is busy (its queue of outside actions is full): not done, try again",
        "no alarm system": "the station has no alarm system",
        "no alarm": "no alarm {alarm!r}", "shelve nobody": "{alarm}: shelving needs the operator's name",
        "shelve no reason": "{alarm}: shelving needs a reason",
        "shelve no duration": "{alarm}: shelving needs a duration of more than 0 s",
        "comment nobody": "{alarm}: a comment needs the operator's name",
        "comment empty": "{alarm}: the comment is empty",
        "silenced": "alarm sound silenced", "NetPlc started": "NetPlc started",
        "NetPlc stopped": "NetPlc stopped",
        "not started": "the station is not started", "running": "NetPlc is running: stop it to step one scan",
        "stepped": "step one scan (scan {scan})",
        "not a pair": "the station is not one of a hot-standby pair ([redundancy])",
        "handing over": "IntoStandBy: the primary role goes to the partner",
        "station quit": "station quit",
        # station.toml's reader (app/station/config.py): its fixed wording; keys, files and values as
        # they are
        "cfg no file": "{file}: no station file here", "cfg not toml": "{file}: not valid TOML: {error}",
        "cfg toml digits": "{file}: not valid TOML: a number of more than {n} digits",
        "cfg toml deep": "{file}: not valid TOML: arrays or tables nested too deeply",
        "cfg missing": "missing", "cfg too large": "a {n}-digit number is too large",
        "cfg expected": "expected {kind}, got {value!r}", "cfg or": " or ",
        "kind bool": "true or false", "kind int": "an integer", "kind float": "a number",
        "kind str": "a string", "kind list": "a list", "kind dict": "a table",
        "cfg outside": "{value} is outside {lo}-{hi}", "cfg empty path": "empty path",
        "cfg nul": "a path cannot hold a NUL character",
        "cfg outside folder": "{path} is outside the station folder {base} (allow_outside = true permits it)",
        "cfg unknown": "unknown setting", "cfg not a file": "{path} is not a file",
        "cfg not one of": "{value!r} is not one of {names}",
        # tags.csv's reader (app/scada/table.py): its fixed wording; columns, names and values as they are
        "tags header": "the header must name the columns {required} (missing: {missing}); known columns: "
                       "{known}",
        "tags unknown column": "unknown column {column!r} (known: {known})",
        "tags column twice": "column {column!r} appears twice",
        "tags fields": "{n} fields, but the header names {header}",
        "tags name used": "the name is already used on line {line}",
        "tag no name given": "(no name)",
        "tag not number": "{key} {text!r} is not a number",
        "tag not finite": "{key} {text!r} is not a finite number",
        "tag not whole": "{key} {text!r} is not a whole number {lo}-{hi}{meaning}",
        "tag when meaning": " (the bit value that is the alarm)",
        "tag priority meaning": " (1 critical, 2 high, 3 medium, 4 low)",
        "tag not yes no": "{key} {text!r} is not yes/no (or 1/0, true/false)",
        "tag no address": "address is missing",
        "tag bad address": "address {text!r} is neither an octal address nor a symbol",
        "tag cannot hold": "address {text!r} cannot hold {what}: {error}",
        "tag bit kind": "an I/O bit or a data bit (byte*8+bit)", "tag value kind": "a {kind} value",
        "tag no name": "name is missing",
        "tag bad name": "{name!r} is not a valid tag name (a letter, then letters, digits or _)",
        "tag bad type": "type {text!r} is not one of {types}",
        "tag bad order": "byte_order {text!r} is not one of {orders} (or {letters})",
        "tag order narrow": "byte_order is for int32 and float32 tags; a {kind} tag is read as NetPlc memory "
                            "holds it",
        "tag scaling partial": "give all of app_min, app_max, phy_min, phy_max or none (missing: {missing})",
        "tag bit scaling": "a bit tag has no conversion (app_min..phy_max must be empty)",
        "tag app undefined": "app_min = app_max = {value:g}: the conversion is undefined",
        "tag phy undefined": "phy_min = phy_max = {value:g}: the conversion is undefined",
        "tag negative": "{key} {value:g} is negative",
        "tag limits order": "{upper} {value:g} is below {lower} {below:g}: the limits must keep the order "
                            "LL <= L <= H <= HH",
        "tag bad suppress": "suppress_by {text!r} is not a bit address or a bit's symbol: {error}",
        "tag bit limits": "a bit tag cannot have limit alarms (HH/H/L/LL); give alarm_when 0 or 1",
        "tag when needs bit": "alarm_when needs a bit tag; {type} takes limit alarms (HH/H/L/LL)",
        "tag limit outside": "{key} {value:g} is outside what a {type} tag can take here ({lo:g}..{hi:g})",
        # the publishers' records (app/publish/mqtt.py, opcua.py, seats.py)
        "mqtt bad bdseq": "MQTT: {file}: not a bdSeq ({error}); starting again at 0",
        "mqtt bdseq not kept": "MQTT: {file}: bdSeq not kept ({error})",
        "mqtt refused": "MQTT broker {peer} refused the connection: {reason}",
        "mqtt connected": "MQTT connected to {peer} as {node} (bdSeq {bdseq}){lost}{waiting}",
        "mqtt dropped": ", {n} NDATA/DDATA dropped so far",
        "mqtt awaiting": "; NBIRTH once primary host {host} is online",
        "mqtt lost": "MQTT connection to {peer} lost ({reason}); reconnecting with back-off, NDATA buffered "
                     "meanwhile",
        "mqtt bad state": "MQTT: STATE of primary host {host} ignored: {error}",
        "mqtt old state": "MQTT: STATE of primary host {host} ignored: its timestamp {stamp} is older than "
                          "{last} (a session of the host's before)",
        "mqtt host online": "MQTT: primary host {host} is online",
        "mqtt rebirth": "MQTT rebirth requested by NCMD via {peer}",
        "mqtt leads": "MQTT: this station leads its pair: connecting as {node} (bdSeq {bdseq})",
        "mqtt follows": "MQTT: this station is the standby of its pair: NDEATH, session ended (bdSeq "
                        "{bdseq}); "
                        "the primary publishes",
        "mqtt host offline": "MQTT: primary host {host} is offline: NDEATH, session ended; a new one once it "
                             "is "
                             "online again, NDATA buffered meanwhile",
        "opcua note": "OPC UA: {note}",
        "opcua untrusted": "OPC UA: client certificate refused, not trusted: {subject} (thumbprint {thumb}), "
                           "kept in {kept}; `python main.py opcua trust {folder} {thumb}` trusts it",
        "opcua connected": "OPC UA: {who} connected ({n} of at most {most} sessions)",
        "opcua disconnected": "OPC UA: {who} disconnected ({n} left)",
        # the archive's own records (registrar/)
        "waiter failed": "archive commit waiter failed: {error}",
        "queue full": "archive queue full: {lost} record(s) lost (the disk did not keep up; queue size "
                      "{size})",
        "writing resumed": "archive writing resumed after {seconds:.0f} s; no records were lost",
        "listener removed": "archive commit listener failed and was removed: {error}",
        "malformed": "archive refused {n} malformed record(s), the first: {first:.300}",
        "write failed kept": "archive write failed: {error}; records are kept in memory and retried",
        "retain crash": "retentive memory restored from the save written at the crash, {file}{why}",
        "retain restored": "retentive memory restored from the {used} save {file}{why}",
        "retain lost after": "retentive memory restored from the {used} save {file}{why}: writes "
                             "acknowledged "
                             "after {when} may be lost",
        "retain why": " ({problems})", "retain zeroes": "retentive memory starts from zeroes ({problems})",
        "retain zeroes lost": "retentive memory starts from zeroes ({problems}): every write acknowledged "
                              "before "
                              "may be lost",
        "save current": "current", "save previous": "previous",
        "current save problem": "current save {problem}", "previous save problem": "previous save {problem}",
        "save missing": "is missing", "save unreadable": "cannot be read: {error}",
        "save truncated": "is truncated",
        "save version": "is not a retentive memory save of this version",
        "save damaged": "is damaged (length or checksum wrong)",
        "save counters": "has unreadable timer and counter values: {error}",
        "retain not renamed": "retentive memory: {tmp} could not become {file}: {error}",
        "retain not saved": "retentive memory could not be saved: {error}; writes are answered all the same "
                            "and "
                            "come back older after a crash until it is saved again",
        "retain saved again": "retentive memory is being saved again",
        "retain waiter failed": "retentive save waiter failed: {error}",
        "states not restored": "alarm states not restored from {file}: {error}; every alarm starts normal "
                               "(the "
                               "file is kept as {damaged})",
        "states restored": "alarm states restored from {file}: {n} alarm(s)",
        "states not saved": "alarm states could not be saved: {error}; kept in memory and retried",
        "states saved again": "alarm states are being saved again",
        "plant lags": "forwarding to the plant archive lags by {lag:.0f} s ({why}); records are kept in the "
                      "local "
                      "archive and sent when it answers",
        "plant slow": "PostgreSQL does not keep up",
        "plant caught up": "forwarding to the plant archive caught up after a lag of up to {lag:.0f} s; no "
                           "records "
                           "were lost",
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
        "user no name": "у пользователя должно быть имя",
        "user exists": "пользователь {name!r} уже есть (пароль меняет passwd)",
        "no user": "нет пользователя {name!r}", "no such role": "роль {role!r} — не одна из: {roles}",
        "empty password": "пароль пуст", "passwords differ": "пароли не совпадают",
        "password changed": "пароль пользователя {user} изменён",
        # netplc/words.py
        "link up": "узел {node} ({endpoint}): связь есть",
        "link down": "узел {node} ({endpoint}): связи нет",
        "link down because": "узел {node} ({endpoint}): связи нет: {error}",
        "write": "запись {where}: {old} -> {new}",
        "write change": "запись {where}: {change} (код {old} -> {new} по адресу {addr})",
        "bits": "{addr}:{n} бит",
        "not io bits": "биты {addr}+{n} — не биты ввода-вывода",
        "write refused": "запись отвергнута: {error}",
        "write failed": "запись из очереди не выполнена: {error}",
        "emergency stop by": "NetPlc остановлен, код 11: бит аварийного останова 03770 записал {user}",
        "watchdog": "сторожевой таймер: скан не дошёл до конца (бесконечный цикл переходов)",
        "listener failed": "обработчик скана {name} отказал (остальные работают): {error}",
        "FON failed": "FON {name} в строке {line}: {error}",
        "peer refused": "сервер Modbus отказал в соединении {peer}: открыто соединений: {n}, с {host} "
                        "(max_per_peer)",
        "server full": "сервер Modbus отказал в соединении {peer}: открыто соединений: {n} (max_connections)",
        "not modbus tcp": "сервер Modbus закрыл соединение {peer}: это не Modbus TCP (протокол {proto}, "
                          "длина {length})",
        "idle half": "сервер Modbus закрыл соединение {peer}: полкадра за {idle:g} с (idle_timeout)",
        "idle nothing": "сервер Modbus закрыл соединение {peer}: ничего не получено за {idle:g} с "
                        "(idle_timeout)",
        "more like it": "{text} (и ещё таких за последнюю минуту: {n})",
        "rtu cannot open": "Modbus RTU на {port}: порт не открывается: {error}",
        "rtu failed": "Modbus RTU на {port}: отказ: {error}",
        "rtu retrying": "{fault}; новая попытка каждые {every:g} с",
        "rtu works": "Modbus RTU на {port} снова работает",
        "force": "фиксация {where}: {was} -> {value}{how}",
        "forced value": "зафиксировано {value}",
        "bumpless": " (безударно)",
        "raw value": "{value} (код {raw})",
        "unforce": "снятие фиксации {where} (было зафиксировано {value})",
        "unforce all": "снятие фиксации {where} (было зафиксировано {value}; снять все)",
        "force kind": "вид фиксации {kind!r} не один из {kinds}",
        "cannot force": "нельзя зафиксировать {kind} {addr}: {error}",
        "does not fit": "{value} не помещается в {kind} (0..{most})",
        "force NaN": "нельзя зафиксировать {name} в значении NaN",
        "addr not octal": "{text!r} — не восьмеричное число",
        "addr not data": "{addr} — не адрес памяти данных",
        "addr past io": "{addr}: операнд из байтов ({n}) выходит за бит 03777",
        "addr not valid": "{addr} — недопустимый адрес",
        "addr past bank": "{addr}: операнд из байтов ({n}) выходит за конец своего банка",
        "addr not bit": "{addr} — ни бит ввода-вывода, ни бит данных (байт*8+бит)",
        "addr not io bit": "{addr} — не бит ввода-вывода",
        "addr not hmi bit": "{addr} — не адрес бита ЧМИ",
        "addr bit past": "бит {k} от {addr} выходит за бит 03777",
        "addr not bytes": "{first}..{last} — не целое число байтов",
        "addr mixes": "{first}..{last} смешивает биты ввода-вывода и память данных",
        "addr missing": "нет операнда",
        "addr no memory": "{addr} не называет памяти: ни бит ввода-вывода (00000-03777), ни байт данных "
                          "(k*010000 + 04000-07777), ни бит данных (байт*8 + бит)",
        "addr too long": "адрес длиной {n} знаков не называет памяти",
        "sym no address": "у символа {name!r} нет адреса",
        "sym bad name": "{name!r} — недопустимое имя символа",
        "sym twice": "символ {name!r} определён дважды",
        "stl too big": "программе нужно слов: {words}; память программ вмещает {most}",
        "stl symbol not octal": "символ {name!r}: {value!r} — не восьмеричный адрес $",
        "stl label twice": "метка {label!r} определена дважды",
        "stl expected": "ожидается инструкция",
        "stl unknown": "неизвестная инструкция {op!r}{hint}",
        "stl label hint": " (после метки нужно двоеточие: '{name}:')",
        "stl cannot read": "не удаётся прочесть параметр в {text!r}",
        "stl no value": "{key}: нет значения",
        "stl no more": "{op} больше параметров не принимает (лишний {token!r})",
        "stl no such param": "у {op} нет параметра {key}:",
        "stl takes none": "{op} не принимает параметров",
        "stl given twice": "параметр {key}: задан дважды",
        "stl not octal address": "{key}: {token!r} — не восьмеричный адрес",
        "stl offset long": "{key}: смещение бита от {name!r} длиннее {n} цифр",
        "stl unknown symbol": "{key}: неизвестный символ {token!r}",
        "stl operand": "{key}: {error}",
        "stl needs c": "{op} нужен C: (адрес бита)",
        "stl not io bit": "C: {addr} — не бит ввода-вывода (00000-03777)",
        "stl coil past": "C: {op} занимает биты {first}-{last}, за битом ввода-вывода 03777",
        "stl const not address": "{key}: здесь нужна константа, а не адрес {token!r}",
        "stl not bcd": "{key}: {token!r} — не двоично-десятичная константа (до 4 десятичных цифр)",
        "stl not octal const": "{key}: {token!r} — не восьмеричное число",
        "stl not decimal": "{key}: {token!r} — не десятичное число",
        "stl outside": "{key}: {token} вне {bounds}",
        "stl needs label": "{op} нужна метка",
        "stl not program address": "L: {token!r} — не восьмеричный адрес программы",
        "stl not start": "L: адрес программы {token} — не начало инструкции",
        "stl undefined label": "L: метка {token!r} не определена",
        "stl needs preset": "{op} нужен N: (уставка 0-255)",
        "stl fon needs n": "FON нужен N: (номер или мнемоника функции)",
        "stl not function number": "N: {token!r} — не номер функции",
        "stl no function": "N: функции {number} нет",
        "stl unknown function": "N: неизвестная функция {token!r}",
        "stl fon no more": "FON {name} больше параметров не принимает (лишний {token!r})",
        "stl takes no key": "{name} не принимает параметра {key}:",
        "stl needs key": "{name} нужен {key}: ({kind})",
        "stl kind M": "адрес", "stl kind O": "восьмеричная константа", "stl kind D": "десятичная константа",
        "stl kind B": "двоично-десятичная константа",
        "modbus not started": "сервер Modbus не запущен: {path}: modbus_server.port: нельзя слушать "
                              "{host}:{port}: {error}",
        "modbus not yet": "сервер Modbus ещё не запущен: {path}: modbus_server.port: {fault}; новая попытка "
                          "каждые {every:g} с",
        "force not restored": "сохранённая фиксация не восстановлена: {problem}",
        "scan failed": "скан отказал: {error}",
        "opcua not started": "сервер OPC UA не запущен: {path}: opcua.endpoint: {error}",
        "opcua started": "сервер OPC UA на {endpoint} ({security}), тегов: {tags}",
        "opcua secure": "Basic256Sha256 Sign&Encrypt, доверенные клиенты",
        "opcua open": "без защиты, только этот компьютер",
        "mqtt started": "публикация MQTT Sparkplug B на {broker} как {node}, метрик: {tags}, устройства: "
                        "{devices}",
        "mqtt primary": "публикация MQTT Sparkplug B на {broker} как {node}, метрик: {tags}, устройства: "
                        "{devices}, главный хост {host}",
        "no devices": "нет",
        "logged in": "вход, роль «{role}»", "logged out": "выход", "logged out idle": "выход: бездействие",
        "logged out switched": "выход: сменился пользователь",
        "joining": "станция входит в пару",
        "pair starting": "станция запускается как одна из пары: команды принимает, когда станет основной",
        "pair standby": "эта станция ({letter}) — резервная: основная — {primary}",
        "nothing to hand over": "в связи пары нет резервной станции, которой передать управление",
        "pair link down": "связи пары с {partner} нет",
        "refused": "отказ: {what}: {why}",
        "refused more": "отказ: {what}: {why} (и ещё таких отказов за минуту до того: {n})",
        "action write": "запись", "action acknowledge": "квитирование", "action shelve": "откладывание",
        "action unshelve": "возврат из отложенных", "action comment": "комментарий",
        "action silence": "отключение звука", "action out of service": "вывод из работы",
        "action force": "фиксация", "action unforce": "снятие фиксации", "action run": "пуск",
        "action stop": "останов", "action step": "один скан", "action quit": "выход из станции",
        "action users": "пользователи", "action trust": "доверие сертификату",
        "action IntoStandBy": "IntoStandBy",
        "action log in": "вход", "action open a session": "открытие сеанса",
        "login waits": "неудачных входов: {n}, с {host}; вход закрыт ещё на {wait:.0f} с",
        "login wrong": "неверное имя пользователя или пароль",
        "login wrong wait": "неверное имя пользователя или пароль; следующие попытки ждут {wait:g} с",
        "sessions full": "[opcua] max_consoles = {n}: столько сеансов уже открыто",
        "role viewer": "наблюдатель", "role operator": "оператор", "role engineer": "инженер",
        "role admin": "администратор",
        "denied source": "нужна роль «{role}»; клиенты без пользователя действуют как «{has}»",
        "denied nobody": "никто не вошёл (нужна роль «{role}»)",
        "denied gone": "{user} больше не пользователь (нужна роль «{role}»)",
        "denied role": "нужна роль «{role}»; {user} — {has}",
        "no tag": "нет тега {name!r}", "no number": "{value!r} — не число",
        "not writable point": "нет среди точек, которые {section} writable разрешает писать",
        "not whole": "{value!r} — не целое", "outside g": "{value} вне диапазона {lo:g} .. {hi:g}",
        "alarm id string": "идентификатор аварии — строка (String)",
        "shelve args": "Shelve принимает причину (String) и число секунд",
        "tag name string": "имя тега — строка (String)",
        "session none": "защита None на {endpoint} — только для поиска (GetEndpoints): сеансу нужен "
                        "Basic256Sha256 Sign&Encrypt",
        "only tags": "по OPC UA пишутся только теги", "no node": "нет такого узла",
        "only value": "у тега пишется только значение, не {attribute}",
        "no device": "у {node} нет такого устройства", "not sparkplug": "не сообщение Sparkplug B ({error})",
        "link metric": "метрика связи, только для чтения", "no metric": "у {node} нет такой метрики",
        "not 0 or 1": "{value!r} — не 0 и не 1", "outside": "{value!r} вне диапазона {lo} .. {hi}",
        "not applied": "{what}: не выполнено (см. журнал)",
        "journal full": "архив не может принять запись (диск полон или слишком медленный): не выполнено",
        "busy": "станция занята (её очередь внешних действий полна): не выполнено, повторите",
        "no alarm system": "у станции нет системы аварий",
        "no alarm": "нет аварии {alarm!r}", "shelve nobody": "{alarm}: для откладывания нужно имя оператора",
        "shelve no reason": "{alarm}: для откладывания нужна причина",
        "shelve no duration": "{alarm}: для откладывания нужен срок больше 0 с",
        "comment nobody": "{alarm}: для комментария нужно имя оператора",
        "comment empty": "{alarm}: комментарий пуст",
        "silenced": "звук аварий отключён", "NetPlc started": "NetPlc запущен",
        "NetPlc stopped": "NetPlc остановлен",
        "not started": "станция не запущена",
        "running": "NetPlc работает: остановите его, чтобы выполнить один скан",
        "stepped": "выполнен один скан (скан {scan})",
        "not a pair": "станция не входит в пару горячего резерва ([redundancy])",
        "handing over": "IntoStandBy: роль основной переходит к партнёру",
        "station quit": "выход из станции",
        "tags header": "заголовок должен назвать столбцы {required} (нет: {missing}); известные столбцы: "
                       "{known}",
        "tags unknown column": "неизвестный столбец {column!r} (известные: {known})",
        "tags column twice": "столбец {column!r} указан дважды",
        "tags fields": "полей {n}, а заголовок называет {header}",
        "tags name used": "имя уже занято в строке {line}",
        "tag no name given": "(без имени)",
        "tag not number": "{key} {text!r} — не число", "tag not finite": "{key} {text!r} — не конечное число",
        "tag not whole": "{key} {text!r} — не целое число {lo}-{hi}{meaning}",
        "tag when meaning": " (значение бита, которое есть авария)",
        "tag priority meaning": " (1 критическая, 2 высокая, 3 средняя, 4 низкая)",
        "tag not yes no": "{key} {text!r} — не yes/no (или 1/0, true/false)",
        "tag no address": "нет address",
        "tag bad address": "address {text!r} — не восьмеричный адрес и не символ",
        "tag cannot hold": "address {text!r} не может вместить {what}: {error}",
        "tag bit kind": "бит ввода-вывода или бит данных (байт*8+бит)", "tag value kind": "значение {kind}",
        "tag no name": "нет name",
        "tag bad name": "{name!r} — недопустимое имя тега (буква, затем буквы, цифры или _)",
        "tag bad type": "type {text!r} — не один из: {types}",
        "tag bad order": "byte_order {text!r} — не один из: {orders} (или {letters})",
        "tag order narrow": "byte_order — для тегов int32 и float32; тег {kind} читается так, как его хранит "
                            "память NetPlc",
        "tag scaling partial": "задайте все app_min, app_max, phy_min, phy_max или ни одного (нет: "
                               "{missing})",
        "tag bit scaling": "у битового тега нет преобразования (app_min..phy_max должны быть пусты)",
        "tag app undefined": "app_min = app_max = {value:g}: преобразование не определено",
        "tag phy undefined": "phy_min = phy_max = {value:g}: преобразование не определено",
        "tag negative": "{key} {value:g} — отрицательное",
        "tag limits order": "{upper} {value:g} ниже {lower} {below:g}: пределы должны идти в порядке "
                            "LL <= L <= H <= HH",
        "tag bad suppress": "suppress_by {text!r} — не адрес бита и не символ бита: {error}",
        "tag bit limits": "у битового тега не бывает аварий по пределам (HH/H/L/LL); задайте alarm_when 0 "
                          "или 1",
        "tag when needs bit": "alarm_when нужен битовый тег; {type} принимает аварии по пределам (HH/H/L/LL)",
        "tag limit outside": "{key} {value:g} вне того, что тег {type} может принять здесь ({lo:g}..{hi:g})",
        "cfg no file": "{file}: здесь нет файла станции", "cfg not toml": "{file}: не TOML: {error}",
        "cfg toml digits": "{file}: не TOML: число длиннее {n} цифр",
        "cfg toml deep": "{file}: не TOML: массивы или таблицы вложены слишком глубоко",
        "cfg missing": "отсутствует", "cfg too large": "число из {n} цифр слишком велико",
        "cfg expected": "ожидается {kind}, а задано {value!r}", "cfg or": " или ",
        "kind bool": "true или false", "kind int": "целое число", "kind float": "число", "kind str": "строка",
        "kind list": "список", "kind dict": "таблица",
        "cfg outside": "{value} вне диапазона {lo}-{hi}", "cfg empty path": "пустой путь",
        "cfg nul": "путь не может содержать символ NUL",
        "cfg outside folder": "{path} вне папки станции {base} (allow_outside = true это разрешает)",
        "cfg unknown": "неизвестный параметр", "cfg not a file": "{path} — не файл",
        "cfg not one of": "{value!r} — не одно из: {names}",
        "mqtt bad bdseq": "MQTT: {file}: не bdSeq ({error}); счёт начинается снова с 0",
        "mqtt bdseq not kept": "MQTT: {file}: bdSeq не сохранён ({error})",
        "mqtt refused": "брокер MQTT {peer} отказал в соединении: {reason}",
        "mqtt connected": "MQTT: соединение с {peer} как {node} (bdSeq {bdseq}){lost}{waiting}",
        "mqtt dropped": ", отброшено NDATA/DDATA: {n}",
        "mqtt awaiting": "; NBIRTH, когда главный хост {host} будет в сети",
        "mqtt lost": "MQTT: соединение с {peer} потеряно ({reason}); повторные попытки с нарастающей паузой, "
                     "NDATA пока копятся",
        "mqtt bad state": "MQTT: STATE главного хоста {host} не принят: {error}",
        "mqtt old state": "MQTT: STATE главного хоста {host} не принят: его метка времени {stamp} старше "
                          "{last} (из прежнего сеанса хоста)",
        "mqtt host online": "MQTT: главный хост {host} в сети",
        "mqtt rebirth": "MQTT: повторное рождение (rebirth) по NCMD через {peer}",
        "mqtt leads": "MQTT: эта станция ведёт пару: соединение как {node} (bdSeq {bdseq})",
        "mqtt follows": "MQTT: эта станция — резервная в паре: NDEATH, сеанс окончен (bdSeq {bdseq}); "
                        "публикует основная",
        "mqtt host offline": "MQTT: главный хост {host} не в сети: NDEATH, сеанс окончен; новый — когда он "
                             "вернётся, NDATA пока копятся",
        "opcua note": "OPC UA: {note}",
        "opcua untrusted": "OPC UA: сертификат клиента отвергнут, ему нет доверия: {subject} (отпечаток "
                           "{thumb}), "
                           "сохранён в {kept}; `python main.py opcua trust {folder} {thumb}` даёт ему "
                           "доверие",
        "opcua connected": "OPC UA: подключился {who} (сеансов {n} из не более чем {most})",
        "opcua disconnected": "OPC UA: отключился {who} (осталось {n})",
        "waiter failed": "ожидающий записи в архив отказал: {error}",
        "queue full": "очередь архива полна: потеряно записей: {lost} (диск не успевал; размер очереди "
                      "{size})",
        "writing resumed": "запись в архив возобновилась через {seconds:.0f} с; записи не потеряны",
        "listener removed": "обработчик записи в архив отказал и удалён: {error}",
        "malformed": "архив отверг неправильных записей: {n}, первая: {first:.300}",
        "write failed kept": "запись в архив не удалась: {error}; записи хранятся в памяти, запись "
                             "повторяется",
        "retain crash": "сохраняемая память восстановлена из сохранения, записанного при сбое, {file}{why}",
        "retain restored": "сохраняемая память восстановлена из {used} сохранения {file}{why}",
        "retain lost after": "сохраняемая память восстановлена из {used} сохранения {file}{why}: записи, "
                             "подтверждённые после {when}, могут быть потеряны",
        "retain why": " ({problems})", "retain zeroes": "сохраняемая память начинается с нулей ({problems})",
        "retain zeroes lost": "сохраняемая память начинается с нулей ({problems}): все подтверждённые ранее "
                              "записи могут быть потеряны",
        "save current": "текущего", "save previous": "предыдущего",
        "current save problem": "текущее сохранение {problem}",
        "previous save problem": "предыдущее сохранение {problem}",
        "save missing": "отсутствует", "save unreadable": "не читается: {error}",
        "save truncated": "обрезано",
        "save version": "не сохранение памяти этой версии",
        "save damaged": "повреждено (неверны длина или контрольная сумма)",
        "save counters": "содержит нечитаемые значения таймеров и счётчиков: {error}",
        "retain not renamed": "сохраняемая память: {tmp} не удалось сделать {file}: {error}",
        "retain not saved": "сохраняемую память не удалось сохранить: {error}; на записи всё равно "
                            "отвечается, "
                            "после сбоя они вернутся более старыми, пока сохранение не удастся",
        "retain saved again": "сохраняемая память снова сохраняется",
        "retain waiter failed": "ожидающий сохранения памяти отказал: {error}",
        "states not restored": "состояния аварий не восстановлены из {file}: {error}; все аварии начинают в "
                               "норме (файл сохранён как {damaged})",
        "states restored": "состояния аварий восстановлены из {file}: аварий {n}",
        "states not saved": "состояния аварий не удалось сохранить: {error}; они хранятся в памяти, запись "
                            "повторяется",
        "states saved again": "состояния аварий снова сохраняются",
        "plant lags": "передача в архив предприятия отстаёт на {lag:.0f} с ({why}); записи хранятся в "
                      "местном "
                      "архиве и будут отправлены, когда он ответит",
        "plant slow": "PostgreSQL не успевает",
        "plant caught up": "передача в архив предприятия догнала после отставания до {lag:.0f} с; записи не "
                           "потеряны",
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
class Phrases:
    """Parts said one after the other, joined by `sep` (a restore's problems, one per file)."""

    parts: Sequence[Phrase]
    sep: str = "; "


@dataclass(frozen=True)
class Words:
    """The catalogue of one language: `words("limit", label=..., ...)` is its text, filled in."""

    language: str

    def __call__(self, name: str, /, **values: object) -> str:
        return TEXTS[self.language][name].format(**{k: self.say(v) for k, v in values.items()})

    def knows(self, name: str) -> bool:
        return name in TEXTS[self.language]

    def say(self, value: object) -> object:
        """A value as it goes into a sentence: a phrase said in this language, the rest as it is."""
        if isinstance(value, Phrases):
            return value.sep.join(str(self.say(part)) for part in value.parts)
        if isinstance(value, WordedError):  # an address's problem, a reader's (netplc/words.py)
            value = value.phrase
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
Journal = Callable[..., None]  # `journal(name, **values)`: a 'system' record of the catalogue (Runtime.say)
