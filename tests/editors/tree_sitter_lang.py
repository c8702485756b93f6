"""The tree-sitter grammar (editors/tree-sitter-elab/) beside the model
language's own parser, for tests/editors/: its parser.c compiled and loaded
with py-tree-sitter, and trees from both in one comparable shape."""

from __future__ import annotations

import ctypes
import functools
import subprocess
from pathlib import Path

import lark
import tree_sitter

from easylab.core.source import ModelError
from easylab.frontend.grammar import grammar_text
from easylab.frontend.inline_c import blank_inline_c
from easylab.frontend.syntax_errors import keyword_as_name

ROOT = Path(__file__).resolve().parents[2]
GRAMMAR_DIR = ROOT / "editors" / "tree-sitter-elab"
CFLAGS = ["-std=c11", "-Wall", "-Wextra", "-Werror", "-O1", "-fPIC", "-shared"]


def compile_language(build_dir: Path) -> tree_sitter.Language:
    """src/parser.c built with gcc (warnings are errors) into a shared
    library and loaded as tree-sitter's ``TSLanguage``."""
    library = build_dir / "elab.so"
    proc = subprocess.run(["gcc", *CFLAGS, "-I", str(GRAMMAR_DIR / "src"), str(GRAMMAR_DIR / "src" / "parser.c"),
                           "-o", str(library)], capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stderr
    function = ctypes.cdll.LoadLibrary(str(library)).tree_sitter_elab
    function.restype = ctypes.c_void_p
    capsule_new = ctypes.pythonapi.PyCapsule_New
    capsule_new.restype = ctypes.py_object
    capsule_new.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_void_p]
    return tree_sitter.Language(capsule_new(function(), b"tree_sitter.Language", None))


@functools.lru_cache(maxsize=1)
def _lark() -> lark.Lark:
    # The front end's parser without its AST transformer: lark's own tree.
    return lark.Lark(grammar_text(), parser="lalr", lexer="contextual", keep_all_tokens=True,
                     maybe_placeholders=False)


def lark_shape(text: str):
    """The front end's parse tree of ``text`` as nested (type, children)
    tuples, tokens as (type, text); None when the front end finds a syntax
    error (inline C included)."""
    try:
        blanked, _ = blank_inline_c(text, "<test>")
        tree = _lark().parse(blanked, on_error=keyword_as_name)
    except (ModelError, lark.exceptions.UnexpectedInput):
        return None
    terminals = {t.name: t for t in _lark().terminals}

    def shape(node):
        if isinstance(node, lark.Token):
            pattern = terminals[node.type].pattern
            kind = pattern.value if pattern.type == "str" else node.type.lower()
            return kind, text[node.start_pos:node.end_pos]
        name = "source_file" if node.data == "start" else str(node.data)
        return name, tuple(shape(child) for child in node.children)

    return shape(tree)


def tree_sitter_shape(node, source: bytes):
    """A tree-sitter tree in lark_shape's form, comments left out."""
    if node.child_count == 0:
        return node.type, source[node.start_byte:node.end_byte].decode("utf-8")
    return node.type, tuple(tree_sitter_shape(child, source) for child in node.children if child.type != "comment")


def first_error(node):
    """The first ERROR or MISSING node of a tree, or None."""
    stack = [node]
    while stack:
        current = stack.pop()
        if current.is_error or current.is_missing:
            return current
        stack.extend(reversed(current.children))
    return None


def _point(source: bytes, offset: int) -> tuple[int, int]:
    return source.count(b"\n", 0, offset), offset - (source.rfind(b"\n", 0, offset) + 1)


def edit_between(tree, old: bytes, new: bytes) -> None:
    """Tell ``tree`` (of ``old``) the one edit that makes ``new`` of it, as
    an editor does: the span between the common prefix and suffix."""
    start = 0
    while start < min(len(old), len(new)) and old[start] == new[start]:
        start += 1
    suffix = 0
    while suffix < min(len(old), len(new)) - start and old[-1 - suffix] == new[-1 - suffix]:
        suffix += 1
    old_end, new_end = len(old) - suffix, len(new) - suffix
    tree.edit(start_byte=start, old_end_byte=old_end, new_end_byte=new_end, start_point=_point(old, start),
              old_end_point=_point(old, old_end), new_end_point=_point(new, new_end))
