"""The registrar's texts by name, in English: the problems of messages.csv. A host with a station
says them in its `Language` (app/scada/words.py holds them with their Russian); without one they
are said in English (`english`)."""

from __future__ import annotations

from netplc.words import WordedError, speaker

WORDS = {
    "msg fields": "expected number,group,type,text but found {n} field(s)",
    "msg type": "type {kind} is not one of 0 info, 1 warning, 2 alarm, 3 critical",
    "msg no text": "message {number} has no text",
    "msg not whole": "{name} {text} is not a non-negative whole number",
    "msg past": "{name} {value} is past {most}, the largest the archive holds",
    "msg defined": "message {number} is already defined on line {line}",
}
english = speaker(WORDS)


class RowError(WordedError):
    """A line of messages.csv that cannot be used."""

    in_english = english
