"""What boards compiling with sdcc 4.2 do when sdcc itself fails on a
correct file (docs/boards.md, "When sdcc crashes").

sdcc's front end narrows an expression cast to a smaller integer type, and
on a narrowed bitwise expression holding a shift past the narrow width,
`(uint8_t)((x * 3u) | (x << 8))`, it crashes (SIGSEGV), in every port.
The same value written `(uint8_t)(uint32_t)((x * 3u) | (x << 8))` is not
narrowed and compiles. ``rescue_source`` makes that rewrite on a
preprocessed file: every cast to an integer type of 16 bits or fewer whose
operand is a bitwise or shift expression (integers only, so no float can
meet the inserted cast) goes through ``uint32_t`` first, which keeps the
low bits, and so the value, of any operand of 32 bits or fewer.

A board calls it only after sdcc failed on the file as written (the
rewrite costs code where narrowing was right), and says what sdcc did when
the rewritten file fails too: a user never sees sdcc's own crash report
alone.
"""

from __future__ import annotations

import re

from pycparser import c_ast, c_generator, c_parser

NARROW = {"int8_t", "uint8_t", "int16_t", "uint16_t", "bool", "_Bool", "char", "short", "signed char",
          "unsigned char", "short int", "unsigned short", "unsigned short int"}
BITWISE = {"|", "^", "&", "<<", ">>"}
# sdcc's own failure rather than an error in the C: a signal, an internal
# error, or the time-out the boards put around it.
CRASHED = re.compile(r"Caught signal|Internal Error|Segmentation fault|did not finish")


_LINE_MARKER = re.compile(r"\s*#\s*(?:line\b|\d)")


def crashed(returncode: int, output: str) -> bool:
    """Did sdcc fail by itself (not on an error in the C)?"""
    return returncode < 0 or returncode in (124, 137, 139) or bool(CRASHED.search(output))


def _type_name(node: c_ast.Node) -> str | None:
    if isinstance(node, c_ast.Typename) and isinstance(node.type, c_ast.TypeDecl) \
            and isinstance(node.type.type, c_ast.IdentifierType):
        return " ".join(node.type.type.names)
    return None


class _Widen(c_ast.NodeVisitor):
    def __init__(self) -> None:
        self.count = 0

    def visit_Cast(self, node: c_ast.Cast) -> None:
        self.generic_visit(node)
        if _type_name(node.to_type) in NARROW and isinstance(node.expr, c_ast.BinaryOp) and node.expr.op in BITWISE:
            wide = c_ast.Typename(None, [], None, c_ast.TypeDecl(None, [], None, c_ast.IdentifierType(["uint32_t"])))
            node.expr = c_ast.Cast(wide, node.expr)
            self.count += 1


def rescue_source(preprocessed: str) -> tuple[str, int]:
    """The rewritten C of a preprocessed file (``uint32_t`` must be
    declared in it) and how many casts changed. Line markers are dropped;
    pragmas stay."""
    text = "\n".join(line for line in preprocessed.splitlines() if not _LINE_MARKER.match(line))
    ast = c_parser.CParser().parse(text)
    widen = _Widen()
    widen.visit(ast)
    return c_generator.CGenerator().visit(ast), widen.count
