"""Re-parsing only the declarations an edit touched.

A file is cut into chunks at the lines where a top-level item starts (a
declaration keyword in the first column). Each chunk is parsed on its own,
preceded by as many line breaks as lines before it so that its spans are
those of the whole file, and remembered by (first line, text). After an
edit only the chunks whose text or first line changed are parsed again;
the file's module is the chunks' modules put together in order.

Items may stand in any order in a file (the grammar is ``start: item*``),
so a file whose chunks each parse is the concatenation of their items.
Where that reasoning does not hold (a chunk that does not parse on its own,
a second ``model`` header) the whole text is parsed, so every syntax error
is the one :func:`parse_text` reports.
"""

from __future__ import annotations

import re

from ..core.source import ModelError
from ..frontend import ast
from ..frontend.parser import parse_text

# The words that open a top-level item (docs/language.md), at the start of a line.
ITEM_START = re.compile(r"^(?:model|import|const|param|var|channel|device|actor|dataflow|chart|task|debug|modbus"
                        r"|node|link|export|remote)\b", re.M)


def chunks(text: str) -> list[tuple[int, str]]:
    """The file's chunks: (lines before the chunk, its text), in order."""
    starts = [m.start() for m in ITEM_START.finditer(text)]
    if not starts or starts[0] != 0:
        starts.insert(0, 0)
    starts.append(len(text))
    out = []
    line = 0
    for begin, end in zip(starts, starts[1:]):
        piece = text[begin:end]
        out.append((line, piece))
        line += piece.count("\n")
    return out


class ChunkedParser:
    """A parser with the signature of :func:`parse_text` that keeps each
    file's chunk modules between calls (one instance per server)."""

    def __init__(self) -> None:
        self._cache: dict[str, dict[tuple[int, str], ast.Module]] = {}
        self.chunks_parsed = 0  # how many chunks were parsed (the benchmark and tests read it)

    def __call__(self, text: str, file: str = "<string>") -> ast.Module:
        old = self._cache.get(file, {})
        new: dict[tuple[int, str], ast.Module] = {}
        modules = []
        try:
            for key in chunks(text):
                module = old.get(key) or new.get(key)
                if module is None:
                    line, piece = key
                    module = parse_text("\n" * line + piece, file)
                    self.chunks_parsed += 1
                new[key] = module
                modules.append(module)
            merged = _merge(file, modules)
        except Exception:  # noqa: BLE001 - whatever a chunk alone raises, the whole text decides
            self._cache.pop(file, None)
            return parse_text(text, file)  # the whole file's own error
        self._cache[file] = new
        return merged


def _merge(file: str, modules: list[ast.Module]) -> ast.Module:
    headers = [m.header for m in modules if m.header is not None]
    if len(headers) > 1:
        raise ModelError([])  # the whole parse names both headers
    return ast.Module(file, headers[0] if headers else None,
                      tuple(i for m in modules for i in m.imports),
                      tuple(d for m in modules for d in m.declarations),
                      tuple(i for m in modules for i in m.interfaces),
                      exports=tuple(e for m in modules for e in m.exports),
                      remote=tuple(r for m in modules for r in m.remote))
