"""The grammar of the model language (elab.lark) and what the AST keeps of
its tokens."""

from __future__ import annotations

import functools
import re
from importlib import resources


@functools.lru_cache(maxsize=1)
def grammar_text() -> str:
    """The Lark grammar (LALR) of ``.elab`` files."""
    return resources.files(__package__).joinpath("elab.lark").read_text(encoding="utf-8")


@functools.lru_cache(maxsize=1)
def kept_terminals() -> frozenset[str]:
    """The terminals the grammar names itself: their tokens reach the AST."""
    return frozenset(re.findall(r"^([A-Z_]+)\s*:", grammar_text(), re.MULTILINE))
