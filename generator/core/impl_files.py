"""C files from the model's folder: actor ``impl`` files and device
handler files. Each is file-scope code and the bodies of blocks a macro
introduces: ``EL_START``/``EL_STEP``/``EL_STOP`` for an actor,
``EL_OPEN``/``EL_START``/``EL_READ``/``EL_WRITE``/``EL_STOP``/``EL_CLOSE``
for a device (docs/language.md)."""

from __future__ import annotations

import re

ACTOR_BLOCKS = ("start", "step", "stop")
DEVICE_BLOCKS = ("open", "start", "read", "write", "stop", "close")
_ANY_BLOCK = re.compile(r"\bEL_(" + "|".join(b.upper() for b in dict.fromkeys(ACTOR_BLOCKS + DEVICE_BLOCKS)) + r")\b")


class ImplFileError(ValueError):
    """A C file from the model's folder that cannot be split, at its line
    and column (1-based)."""

    def __init__(self, file: str, line: int, column: int, message: str):
        super().__init__(f"{file}:{line}:{column}: {message}")
        self.file, self.line, self.column, self.message = file, line, column, message


def split_impl(text: str, file: str, blocks: tuple[str, ...] = ACTOR_BLOCKS,
               spans: dict[str, tuple[int, int, int]] | None = None) -> tuple[str, dict[str, str]]:
    """Split a C file into its file-scope code and the bodies of its blocks
    (``blocks``, lower case; comments and strings skipped). A block macro of
    the other kind of file, or a block given twice, is an ImplFileError at
    its place. ``spans``, when given, receives each block's offsets in
    ``text``: (its macro, its body's first character, its closing brace)."""
    masked = _mask_c(text)

    def where(offset: int) -> tuple[int, int]:
        return masked.count("\n", 0, offset) + 1, offset - (masked.rfind("\n", 0, offset) + 1) + 1

    bodies: dict[str, str] = {}
    prelude = []
    pos = 0
    for m in _ANY_BLOCK.finditer(masked):
        kind = m.group(1).lower()
        if kind not in blocks:
            raise ImplFileError(file, *where(m.start()), f"EL_{m.group(1)} is not a block of this file; its blocks "
                                "are " + ", ".join(f"EL_{b.upper()}" for b in blocks))
        if kind in bodies:
            raise ImplFileError(file, *where(m.start()), f"EL_{m.group(1)} is given twice")
        open_at = masked.find("{", m.end())
        if open_at < 0 or masked[m.end():open_at].strip():
            raise ImplFileError(file, *where(m.start()), f"EL_{m.group(1)} must be followed by a block {{ ... }}")
        depth, k = 0, open_at
        while k < len(masked):
            if masked[k] == "{":
                depth += 1
            elif masked[k] == "}":
                depth -= 1
                if depth == 0:
                    break
            k += 1
        if k >= len(masked):
            raise ImplFileError(file, *where(open_at), f"the block of EL_{m.group(1)} is never closed")
        prelude.append(text[pos:m.start()])
        bodies[kind] = text[open_at + 1:k]
        if spans is not None:
            spans[kind] = (m.start(), open_at + 1, k)
        pos = k + 1
    prelude.append(text[pos:])
    return "".join(prelude), bodies


def _mask_c(text: str) -> str:
    """``text`` with C comments and string/char literals replaced by spaces."""
    out = list(text)
    i, n = 0, len(text)
    while i < n:
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
        elif text[i] in "\"'":
            quote, j = text[i], i + 1
            while j < n and text[j] != quote and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j += 1
        else:
            i += 1
            continue
        for k in range(i, min(j, n)):
            if out[k] != "\n":
                out[k] = " "
        i = j
    return "".join(out)
