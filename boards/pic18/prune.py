"""Functions no code reaches, left out of a PIC18 build.

gplink keeps every function of every object it links (it has no
counterpart of `--gc-sections`), and sdcc compiles every function of a file,
even an unused `static inline` one of a header. The build sees the whole
program's portable C parsed (lower64.py needs it anyway), so it drops the
functions that nothing reaches from the roots: `main`, the interrupt
handler, whatever the hardware files name, and every function a data
object's initializer names (tables of function pointers). Data objects are
kept (a simulation traces items no code reads), but for a file's own
read-only tables (`static const`) that nothing left in the file reads: a
runtime file's table for code the model does not use (el_crc16.c's tables
without a Modbus slave).
"""

from __future__ import annotations

from pycparser import c_ast


class _Refs(c_ast.NodeVisitor):
    def __init__(self):
        self.names: set[str] = set()

    def visit_ID(self, node: c_ast.ID) -> None:
        self.names.add(node.name)


def _refs(node: c_ast.Node | None) -> set[str]:
    v = _Refs()
    if node is not None:
        v.visit(node)
    return v.names


def _static(decl: c_ast.Decl) -> bool:
    return "static" in (decl.storage or [])


def is_const(decl: c_ast.Decl) -> bool:
    """A declaration of a const object (or an array of const elements)."""
    node = decl.type
    while isinstance(node, c_ast.ArrayDecl):
        node = node.type
    return "const" in (getattr(node, "quals", None) or [])


def _unread_table(decl: c_ast.Node, used: set[str]) -> bool:
    return isinstance(decl, c_ast.Decl) and not isinstance(decl.type, c_ast.FuncDecl) and _static(decl) \
        and is_const(decl) and decl.name is not None and decl.name not in used


def prune(units: dict[str, c_ast.FileAST], roots: set[str]) -> list[str]:
    """Remove unreachable function definitions from ``units`` (file name ->
    AST) in place; returns the names removed, sorted."""
    defs: dict[tuple[str, str], c_ast.FuncDef] = {}  # (unit or "" for external linkage, name)
    uses: dict[tuple[str, str], set[str]] = {}
    todo: list[tuple[str, str]] = []
    data_refs: list[tuple[str, set[str]]] = []
    for unit, ast in units.items():
        for ext in ast.ext:
            if isinstance(ext, c_ast.FuncDef):
                key = (unit if _static(ext.decl) else "", ext.decl.name)
                defs[key] = ext
                uses[key] = _refs(ext.body)
            elif isinstance(ext, c_ast.Decl) and ext.init is not None:
                data_refs.append((unit, _refs(ext.init)))

    def resolve(unit: str, name: str) -> tuple[str, str] | None:
        for key in ((unit, name), ("", name)):
            if key in defs:
                return key
        return None

    todo += [("", name) for name in roots if ("", name) in defs]
    for unit, names in data_refs:
        todo += [k for k in (resolve(unit, n) for n in names) if k is not None]
    reached: set[tuple[str, str]] = set()
    while todo:
        key = todo.pop()
        if key in reached:
            continue
        reached.add(key)
        unit = key[0] or next(u for u, ast in units.items() if defs[key] in ast.ext)
        todo += [k for k in (resolve(unit, n) for n in uses[key]) if k is not None and k not in reached]
    removed = []
    for unit, ast in units.items():
        kept = []
        for ext in ast.ext:
            if isinstance(ext, c_ast.FuncDef):
                key = (unit if _static(ext.decl) else "", ext.decl.name)
                if key not in reached:
                    removed.append(ext.decl.name)
                    continue
            kept.append(ext)
        used = _refs(c_ast.FileAST(kept))
        ast.ext = [ext for ext in kept if not _unread_table(ext, used)]
    return sorted(removed)
