"""Actor ``impl`` files: their file-scope code and the bodies of their
``EL_START``/``EL_STEP``/``EL_STOP`` blocks (docs/language.md)."""

from __future__ import annotations

import re

_BLOCK_MACRO = re.compile(r"\bEL_(START|STEP|STOP)\b")


def split_impl(text: str, file: str) -> tuple[str, dict[str, str]]:
    """Split an impl file into its file-scope code and the bodies of its
    ``EL_START``/``EL_STEP``/``EL_STOP`` blocks (comments and strings skipped)."""
    masked = _mask_c(text)
    bodies: dict[str, str] = {}
    prelude = []
    pos = 0
    for m in _BLOCK_MACRO.finditer(masked):
        kind = m.group(1).lower()
        open_at = masked.find("{", m.end())
        if open_at < 0 or masked[m.end():open_at].strip():
            raise ValueError(f"{file}: EL_{m.group(1)} must be followed by a block {{ ... }}")
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
            raise ValueError(f"{file}: the block of EL_{m.group(1)} is never closed")
        prelude.append(text[pos:m.start()])
        bodies[kind] = text[open_at + 1:k]
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
