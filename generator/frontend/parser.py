"""Parsing ``.elab`` text into the AST (docs/language.md): inline C blocks
are blanked first (inline_c.py), the LALR parser builds the AST as it
reduces (to_ast.py), and a syntax error becomes one diagnostic in the
model's words (syntax_errors.py)."""

from __future__ import annotations

import functools
import hashlib
import os
import sys
import threading
from pathlib import Path

import lark
from lark.exceptions import UnexpectedInput, VisitError

from ..core.source import ModelError
from . import ast
from .grammar import grammar_text as _grammar_text
from .inline_c import blank_inline_c
from .syntax_errors import keyword_as_name, syntax_error
from .to_ast import ToAst

_PARSE_LOCK = threading.Lock()


@functools.lru_cache(maxsize=1)
def _ast_parser() -> tuple[lark.Lark, ToAst]:
    """A parser that builds the AST while parsing. The transformer is told
    the file and its inline C before each parse; parsing holds a lock."""
    transformer = ToAst("<string>", {})
    text = _grammar_text()
    options = dict(parser="lalr", lexer="contextual", keep_all_tokens=True, maybe_placeholders=False,
                   transformer=transformer, lexer_callbacks={"NAME": transformer.checked_name})
    return _cached_lark(text, options), transformer


def _cached_lark(text: str, options: dict) -> lark.Lark:
    """The LALR parser of ``text``, its tables cached on disk (every command
    builds it otherwise: a third of `easylab check`'s time). The cache file
    is named by the grammar, lark's and Python's versions and is written
    whole or not at all; a cache that cannot be written is no error."""
    key = hashlib.sha256(f"{text}\0{sorted(options)}\0{lark.__version__}\0{sys.version_info[:2]}".encode())
    base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    path = Path(base) / "easylab" / f"grammar-{key.hexdigest()[:24]}.lark"
    if path.is_file():
        return lark.Lark(text, cache=str(path), **options)
    temp = path.with_name(f"{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        parser = lark.Lark(text, cache=str(temp), **options)
        os.replace(temp, path)
        return parser
    except OSError:
        try:
            temp.unlink(missing_ok=True)
        except OSError:
            pass  # no folder to write in
        return lark.Lark(text, **options)


def parse_text(text: str, file: str = "<string>") -> ast.Module:
    """Parse model text into an :class:`ast.Module`; raise :class:`ModelError`."""
    blanked, blocks = blank_inline_c(text, file)
    parser, transformer = _ast_parser()
    with _PARSE_LOCK:
        transformer.file, transformer.blocks, transformer.depths = file, blocks, {}
        try:
            return parser.parse(blanked, on_error=keyword_as_name)
        except UnexpectedInput as err:
            raise ModelError([syntax_error(err, file, blanked, parser)]) from None
        except VisitError as err:
            if isinstance(err.orig_exc, ModelError):
                raise err.orig_exc from None
            raise
