"""Static functions called once, written in place of their call.

sdcc's pic16 port passes arguments on its software stack and saves the
registers a function uses: a call costs dozens of cycles. Generated code
calls each actor's step function (a static function) from exactly one
place, its dataflow's schedule, and the dataflow function from its task's
body: written in place, the activation runs without those calls. (sdcc's
own `inline` does it too, but keeps a copy of every inlined function, which
costs program memory.)

A function is written in place when it is static, returns void, takes a
fixed number of arguments, is named nowhere but in one call that is a
statement of its own, and does not call itself. The call becomes a block:
the arguments into temporaries, then the parameters from them (so that an
argument naming something a parameter shadows still means the caller's),
then the body, each `return;` a jump to the block's end. Actor code
written into a function above the pragma that precedes it (sdcc's warning
94 off for actor code) moves the pragma up before that function.
"""

from __future__ import annotations

import copy

from pycparser import c_ast


# Generated C gives actor code last, after this pragma (runtime_c/
# el_actor_code.h: sdcc's warning 94 off to the end of the file).
ACTOR_CODE_PRAGMA = "disable_warning 94"


class _Sites(c_ast.NodeVisitor):
    """Every name use; calls that are statements of their own, with the
    function they are in."""

    def __init__(self):
        self.named: dict[str, int] = {}
        # name -> (block, index, the calling function's name)
        self.statement_calls: dict[str, list[tuple[c_ast.Node, int, str]]] = {}
        self._function = ""

    def visit_FuncDef(self, node: c_ast.FuncDef) -> None:
        self._function = node.decl.name
        self.generic_visit(node)

    def visit_ID(self, node: c_ast.ID) -> None:
        self.named[node.name] = self.named.get(node.name, 0) + 1

    def visit_Compound(self, node: c_ast.Compound) -> None:
        for k, item in enumerate(node.block_items or []):
            if isinstance(item, c_ast.FuncCall) and isinstance(item.name, c_ast.ID):
                self.statement_calls.setdefault(item.name.name, []).append((node, k, self._function))
        self.generic_visit(node)


def _actor_code_first(ast: c_ast.FileAST, actor_code: set[str]) -> None:
    """The actor code pragma before the first function that holds actor
    code: written in place, an actor's step runs in its dataflow's function
    (and that in its task's), above the pragma."""
    pragma = next((e for e in ast.ext if isinstance(e, c_ast.Pragma) and e.string.strip() == ACTOR_CODE_PRAGMA),
                  None)
    if pragma is None:
        return
    first = next((k for k, e in enumerate(ast.ext) if isinstance(e, c_ast.FuncDef) and e.decl.name in actor_code),
                 None)
    if first is not None and first < ast.ext.index(pragma):
        ast.ext.remove(pragma)
        ast.ext.insert(first, pragma)


class _Returns(c_ast.NodeVisitor):
    def __init__(self):
        self.values = False
        self.labels: list[str] = []

    def visit_Return(self, node: c_ast.Return) -> None:
        self.values = self.values or node.expr is not None

    def visit_Label(self, node: c_ast.Label) -> None:
        self.labels.append(node.name)
        self.generic_visit(node)


def _returns_to(node: c_ast.Node, label: str) -> c_ast.Node:
    """The body with each `return;` as `goto label;`."""
    if isinstance(node, c_ast.Return):
        return c_ast.Goto(label)
    node = copy.copy(node)
    for name, child in node.children():
        base = name.split("[")[0]
        if "[" in name:
            items = list(getattr(node, base))
            items[int(name.split("[")[1].rstrip("]"))] = _returns_to(child, label)
            setattr(node, base, items)
        else:
            setattr(node, base, _returns_to(child, label))
    return node


def _is_void(fd: c_ast.FuncDecl) -> bool:
    t = fd.type
    return isinstance(t, c_ast.TypeDecl) and isinstance(t.type, c_ast.IdentifierType) and t.type.names == ["void"]


def _params(fd: c_ast.FuncDecl) -> list[c_ast.Decl] | None:
    """The named parameters, or None when the list is not a plain one."""
    out = []
    for p in (fd.args.params if fd.args else []):
        if isinstance(p, c_ast.Typename) and isinstance(p.type, c_ast.TypeDecl) and \
                isinstance(p.type.type, c_ast.IdentifierType) and p.type.type.names == ["void"]:
            continue
        if not isinstance(p, c_ast.Decl) or not p.name or isinstance(p.type, (c_ast.ArrayDecl, c_ast.FuncDecl)):
            return None
        out.append(p)
    return out


def inline_single_calls(ast: c_ast.FileAST) -> list[str]:
    """Write the unit's static functions called once in place of the call,
    in place; returns their names."""
    done = []
    serial = 0
    changed = True
    pragma = next((k for k, e in enumerate(ast.ext) if isinstance(e, c_ast.Pragma)
                   and e.string.strip() == ACTOR_CODE_PRAGMA), len(ast.ext))
    actor_code = {e.decl.name for e in ast.ext[pragma:] if isinstance(e, c_ast.FuncDef)}
    while changed:
        changed = False
        sites = _Sites()
        sites.visit(ast)
        for ext in list(ast.ext):
            if not isinstance(ext, c_ast.FuncDef) or "static" not in (ext.decl.storage or []):
                continue
            name, fd = ext.decl.name, ext.decl.type
            calls = sites.statement_calls.get(name, [])
            params = _params(fd)
            if len(calls) != 1 or sites.named.get(name, 0) != 1 or params is None or not _is_void(fd):
                continue
            block, index, caller = calls[0]
            call = block.block_items[index]
            args = call.args.exprs if call.args else []
            returns = _Returns()
            returns.visit(ext.body)
            if len(args) != len(params) or returns.values or block is ext.body:
                continue
            serial += 1
            end = f"el_inl{serial}_end"
            temps, inner = [], []
            for k, (p, arg) in enumerate(zip(params, args)):
                temp = f"el_inl{serial}_a{k}"
                tdecl = copy.deepcopy(p)
                _rename(tdecl, temp)
                tdecl.init = arg
                temps.append(tdecl)
                pdecl = copy.deepcopy(p)
                pdecl.init = c_ast.ID(temp)
                inner.append(pdecl)
            body = _returns_to(ext.body, end)
            inner.append(body)
            inner.append(c_ast.Label(end, c_ast.EmptyStatement()))
            block.block_items[index] = c_ast.Compound(temps + [c_ast.Compound(inner)])
            ast.ext.remove(ext)
            for proto in [e for e in ast.ext if isinstance(e, c_ast.Decl) and e.name == name]:
                ast.ext.remove(proto)
            done.append(name)
            if name in actor_code:
                actor_code.add(caller)
            changed = True
            break  # the sites moved: look again
    _actor_code_first(ast, actor_code)
    return done


def _rename(decl: c_ast.Decl, name: str) -> None:
    decl.name = name
    node = decl.type
    while not isinstance(node, c_ast.TypeDecl):
        node = node.type
    node.declname = name
