"""sdcc's messages about model.c in the model's words.

The C that sdcc compiles is lowered (obj/NAME.sdcc.c) but carries `#line`
markers, so a message names model.c's line. model.c marks each actor
type's code with a comment `/* Name, FILE.elab:LINE */` and copies its
inline C line for line: a message on such a line also names the actor
type and the line of the model file that holds the same text.
"""

from __future__ import annotations

import re
from pathlib import Path

_MESSAGE = re.compile(r"^(?P<file>\S*model\.c):(?P<line>\d+):(?P<rest>.*)$")
# an actor specialisation's heading: `/* Name<T, ..>(arg = v, ..), FILE.elab:LINE */`
_ACTOR = re.compile(r"^/\* (?P<name>\w+)(?:<[^>]*>)?(?:\(.*\))?, (?P<file>.+\.elab):(?P<line>\d+) \*/$")


def in_model_terms(message: str) -> str:
    """The message with each line about model.c preceded by the model file's
    line (when found) and followed by the actor type it is in."""
    return "\n".join(_line(text) for text in message.split("\n"))


def _line(text: str) -> str:
    m = _MESSAGE.match(text)
    if not m:
        return text
    try:
        lines = Path(m.group("file")).read_text(encoding="utf-8").split("\n")
    except OSError:
        return text
    number = int(m.group("line"))
    actor = None
    for k in range(min(number, len(lines)) - 1, -1, -1):
        a = _ACTOR.match(lines[k].strip())
        if a:
            actor = a
            break
        if lines[k].startswith("/* ===="):
            break
    if actor is None:
        return text
    where = f"{actor.group('file')}:{actor.group('line')}"
    wanted = lines[number - 1].strip() if number <= len(lines) else ""
    try:
        model = Path(actor.group("file")).read_text(encoding="utf-8").split("\n")
    except OSError:
        model = []
    start = int(actor.group("line"))
    found = next((start + k for k, line in enumerate(model[start - 1:]) if wanted and line.strip() == wanted), None)
    head = f"{actor.group('file')}:{found}:" if found else f"{where}:"
    return f"{head}{m.group('rest')} (in actor type {actor.group('name')}, {where}; {m.group('file')}:{number})"
