"""Inline C blocks (``{{ ... }}``): they run to the ``}}`` that balances the
opening ``{{``, which no regular expression can find. Before lexing, the C
text is blanked out (line breaks kept, so every position stays right) and
kept aside by its offset; the grammar's ``C_CODE`` terminal matches the
blanked block and the transformer puts the text back."""

from __future__ import annotations

from ..core.source import Diagnostic, ModelError, Span


def position(text: str, offset: int) -> tuple[int, int]:
    line = text.count("\n", 0, offset) + 1
    return line, offset - (text.rfind("\n", 0, offset) + 1) + 1


def blank_inline_c(text: str, file: str) -> tuple[str, dict[int, str]]:
    """Blank the C text of every ``{{ ... }}`` block; return it by offset.

    Comments and strings of the model language are skipped, so a ``{{`` in a
    comment opens nothing. Raises :class:`ModelError` for an unclosed block.
    """
    blocks: dict[int, str] = {}
    out: list[str] = []
    i, n, copied = 0, len(text), 0
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            end = text.find("\n", i)
            i = n if end < 0 else end
        elif text.startswith("/*", i):
            end = text.find("*/", i + 2)
            i = n if end < 0 else end + 2
        elif c == '"':
            i += 1
            while i < n and text[i] not in '"\n':
                i += 2 if text[i] == "\\" else 1
            i += 1
        elif text.startswith("{{", i):
            depth, k = 0, i
            while k < n:
                if text[k] == "{":
                    depth += 1
                elif text[k] == "}":
                    depth -= 1
                    if depth == 0:
                        break
                k += 1
            if k >= n or text[k - 1] != "}":  # the braces close, but not with '}}'
                line, col = position(text, i)
                raise ModelError([Diagnostic(Span(file, line, col, line, col + 2),
                                             "inline C block '{{' is never closed by a balancing '}}'",
                                             "braces inside inline C, in its strings and comments too, must balance")])
            body = text[i + 2:k - 1]
            blocks[i] = body
            out.append(text[copied:i + 2])
            out.append("".join(ch if ch == "\n" else " " for ch in body))
            out.append("}}")
            copied = i = k + 1
        else:
            i += 1
    out.append(text[copied:])
    return "".join(out), blocks
