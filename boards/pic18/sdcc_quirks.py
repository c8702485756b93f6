"""What sdcc 4.2's pic16 port gets wrong about valid C, and how the PIC18
build works around it on the whole program's syntax trees (after the
64-bit lowering) and on sdcc's assembly. Each was found compiling the
runtime and the generated tables, and each is checked by the board's tests
(tests/pic18/, the conformance traces).

- RAM objects larger than a bank: gplink keeps every section inside one
  256-byte bank, so they could not be placed. They get fixed addresses at
  the top of RAM (`__at`), each on a 4-byte boundary so that no element of
  1, 2 or 4 bytes straddles two banks (sdcc selects a bank per access to a
  constant element). sdcc reserves a `static` object with `__at` twice
  (its own section and the fixed one: gpasm refuses the duplicate label),
  so such an object loses `static` and takes a name unique to its unit.
  A function's local array of that size (without an initializer) gets a
  section of its own too: it becomes a static object of its file first.
- A generic pointer initialised with the address of a struct member in RAM
  (`(void *)&s.count` in the debugger's tables) gets the tag of program
  memory (sdcc: "initialized generic pointer with unknown storage class
  assumes object in code space"): the tag byte is set to RAM's (0x80) in
  the assembly of every object the program keeps in RAM.
- An array member converted to a pointer in a static initializer
  (`(void *)s.window`) is refused ("pointer types incompatible"), while
  `&s.window[0]` is right: initializers are rewritten so.
- sdcc puts every initialised RAM object of a file in one `idata`
  section, which gplink must place in one bank: a model with more than
  256 bytes of items (each item is initialised, most to zero) did not
  link. An initializer of zeros only is dropped: start-up clears RAM
  (pic18_startup.c), as C's zero initialisation wants, and such an object
  goes to a section of its own, with no initial value in program memory.
"""

from __future__ import annotations

import re

from pycparser import c_ast

from .ctypes64 import LowerError, Target, TypeEnv, const_value
from .prune import is_const

BANK_BYTES = 256
FIRST_BANK = 0x080  # RAM below is the access bank (sdcc's registers, small objects)


def _objects(ast: c_ast.FileAST, target: Target):
    """(declaration, its type, the environment) of each object declared at
    file scope, in order."""
    env = TypeEnv(target)
    for ext in ast.ext:
        if isinstance(ext, c_ast.Typedef):
            env.typedef(ext)
        elif isinstance(ext, c_ast.Decl) and not isinstance(ext.type, c_ast.FuncDecl):
            t = env.of_decl(ext.type)
            if ext.name:
                env.declare(ext.name, t)
            yield ext, t, env


def place_big_objects(units: dict[str, c_ast.FileAST], target: Target, ram_end: int) -> int:
    """Give every RAM object larger than a bank a fixed address, from
    ``ram_end`` (the last byte) down. Returns the lowest address placed
    (``ram_end`` + 1 when none); BigObjectsDoNotFit when they take more
    than the RAM above the access bank."""
    top = ram_end + 1
    placed: list[tuple[str, int]] = []
    for unit, ast in units.items():
        _hoist_big_locals(ast, target)
        big: dict[str, int] = {}
        used = _used_names(ast)
        dead = set()
        for decl, t, env in _objects(ast, target):
            size = env.size(t)
            if decl.name and "extern" not in (decl.storage or []) and not is_const(decl) and size is not None \
                    and size > BANK_BYTES:
                if "static" in (decl.storage or []) and decl.name not in used:
                    dead.add(decl.name)  # no code left reads it (prune.py): sdcc would declare it, not define it
                    continue
                top = (top - size) & ~3
                big[decl.name] = top
                placed.append((decl.name, size))
        for ext in ast.ext:
            if isinstance(ext, c_ast.Decl) and ext.name in big and not isinstance(ext.type, c_ast.FuncDecl):
                address = big[ext.name]
                if "static" in (ext.storage or []):
                    _rename(ast, ext.name, f"{ext.name}__{re.sub(r'[^A-Za-z0-9_]', '_', unit)}")
                    ext.storage = [s for s in ext.storage if s != "static"]
                ext.storage = [f"__at(0x{address:03X})", *(ext.storage or [])]
        ast.ext = [ext for ext in ast.ext if not (isinstance(ext, c_ast.Decl) and ext.name in dead)]
    if top < FIRST_BANK:
        raise BigObjectsDoNotFit(ram_end + 1 - FIRST_BANK, sorted(placed, key=lambda p: -p[1]))
    return top


def _hoist_big_locals(ast: c_ast.FileAST, target: Target) -> None:
    """A function's local array larger than a bank, without an initializer,
    becomes a static object of the file, declared before the function and
    named ``NAME__FUNCTION_N``: sdcc keeps a local of these functions in
    static RAM anyway (none is reentrant), but in a section of its own that
    no bank holds; at file scope it is placed like the other big objects
    (a min-buffer schedule's tokens copied out of a ring for one firing)."""
    env = TypeEnv(target)
    out = []
    for ext in ast.ext:
        if isinstance(ext, c_ast.Typedef):
            env.typedef(ext)
        elif isinstance(ext, c_ast.Decl) and not isinstance(ext.type, c_ast.FuncDecl):
            env.of_decl(ext.type)  # its struct's members, for the sizes of locals
        elif isinstance(ext, c_ast.FuncDef):
            hoister = _BigLocals(env, ext.decl.name)
            hoister.visit(ext.body)
            out += hoister.hoisted
        out.append(ext)
    ast.ext = out


class _BigLocals(c_ast.NodeVisitor):
    """The big local arrays of one function's body, taken out of their
    blocks (``hoisted``) with their uses renamed."""

    def __init__(self, env: TypeEnv, function: str):
        self.env, self.function = env, function
        self.hoisted: list[c_ast.Decl] = []

    def _big(self, item: c_ast.Node) -> bool:
        if not isinstance(item, c_ast.Decl) or item.init is not None or item.storage \
                or not isinstance(item.type, c_ast.ArrayDecl):
            return False
        try:
            size = self.env.size(self.env.of_decl(item.type))
        except LowerError:
            return False
        return size is not None and size > BANK_BYTES

    def visit_Compound(self, node: c_ast.Compound) -> None:
        items = node.block_items or []
        kept = []
        for i, item in enumerate(items):
            if self._big(item):
                new = f"{item.name}__{self.function}_{len(self.hoisted)}"
                for later in items[i + 1:]:
                    _LocalRenamer(item.name, new).visit(later)
                _rename(c_ast.FileAST([item]), item.name, new)
                item.storage = ["static"]
                self.hoisted.append(item)
                continue
            kept.append(item)
            self.visit(item)
        node.block_items = kept


class _LocalRenamer(c_ast.NodeVisitor):
    """The uses of a block's local in the statements after its declaration,
    up to a declaration of the same name in an inner block."""

    def __init__(self, old: str, new: str):
        self.old, self.new = old, new

    def visit_ID(self, node: c_ast.ID) -> None:
        if node.name == self.old:
            node.name = self.new

    def visit_Compound(self, node: c_ast.Compound) -> None:
        for item in node.block_items or []:
            if isinstance(item, c_ast.Decl) and item.name == self.old:
                return  # shadowed from here on
            self.visit(item)


def _used_names(ast: c_ast.FileAST) -> set[str]:
    """The identifiers a unit's code and initializers use."""
    class Uses(c_ast.NodeVisitor):
        def __init__(self):
            self.names: set[str] = set()

        def visit_ID(self, node):
            self.names.add(node.name)

    uses = Uses()
    uses.visit(ast)
    return uses.names


def _rename(ast: c_ast.FileAST, old: str, new: str) -> None:
    """A file-scope object's new name, in its declarations and uses (the
    runtime's units declare no local of the same name)."""
    class Renamer(c_ast.NodeVisitor):
        def visit_ID(self, node):
            if node.name == old:
                node.name = new

        def visit_Decl(self, node):
            if node.name == old:
                node.name = new
                t = node.type
                while not isinstance(t, c_ast.TypeDecl):
                    t = t.type
                t.declname = new
            self.generic_visit(node)

    Renamer().visit(ast)


class BigObjectsDoNotFit(Exception):
    """The objects larger than a bank need more RAM than there is."""

    def __init__(self, room: int, objects: list[tuple[str, int]]):
        self.room, self.objects = room, objects
        total = sum(size for _, size in objects)
        super().__init__(f"the RAM objects larger than a bank take {total} bytes, more than the {room} bytes of "
                         f"RAM between the access bank and the stack: " + ", ".join(f"{n} {s} B" for n, s in objects[:6]))


class _ArrayMembers(c_ast.NodeVisitor):
    """In an initializer: an array member used as a pointer -> &member[0]."""

    def __init__(self, env: TypeEnv):
        self.env = env

    def _fix(self, node: c_ast.Node) -> c_ast.Node:
        if isinstance(node, c_ast.StructRef):
            base = self._type(node.name)
            if node.type == "->" and base.to is not None:
                base = base.to
            if self.env.member(base, node.field.name, node).kind == "array":
                return c_ast.UnaryOp("&", c_ast.ArrayRef(node, c_ast.Constant("int", "0")))
        return node

    def _type(self, node: c_ast.Node):
        if isinstance(node, c_ast.ID):
            return self.env.lookup(node.name)
        if isinstance(node, c_ast.StructRef):
            base = self._type(node.name)
            return self.env.member(base.to if node.type == "->" and base.to else base, node.field.name, node)
        return self.env.lookup("")

    def visit_Cast(self, node: c_ast.Cast) -> None:
        node.expr = self._fix(node.expr)
        self.generic_visit(node)

    def visit_InitList(self, node: c_ast.InitList) -> None:
        node.exprs = [self._fix(e) for e in node.exprs]
        self.generic_visit(node)


def fix_initializers(units: dict[str, c_ast.FileAST], target: Target) -> set[str]:
    """Rewrite array members in static initializers; returns the names of
    the objects the program keeps in RAM (for ram_pointer_tags)."""
    in_ram: set[str] = set()
    for ast in units.values():
        for decl, _t, env in _objects(ast, target):
            if decl.init is not None:
                _ArrayMembers(env).visit(decl.init)
            if decl.name and not is_const(decl):
                in_ram.add(decl.name)
    return in_ram


def _zeros(init: c_ast.Node) -> bool:
    """An initializer whose every value is the constant 0."""
    if isinstance(init, c_ast.InitList):
        return all(_zeros(e.expr if isinstance(e, c_ast.NamedInitializer) else e) for e in init.exprs)
    if isinstance(init, c_ast.Cast):
        return _zeros(init.expr)
    if isinstance(init, c_ast.Constant) and init.type not in ("string", "float", "double"):
        try:
            return const_value(init) == 0
        except LowerError:
            return False
    return False


def drop_zero_initializers(units: dict[str, c_ast.FileAST]) -> int:
    """Drop the initializers of zeros of file-scope RAM objects; returns how many."""
    count = 0
    for ast in units.values():
        for ext in ast.ext:
            if isinstance(ext, c_ast.Decl) and ext.init is not None and not isinstance(ext.type, c_ast.FuncDecl) \
                    and not is_const(ext) and "extern" not in (ext.storage or []) and _zeros(ext.init):
                ext.init = None
                count += 1
    return count


_UPPER = re.compile(r"UPPER\(\(?_([A-Za-z_]\w*)(?:\s*\+\s*\d+)?\)?\)")


def ram_pointer_tags(asm: str, in_ram: set[str]) -> str:
    """sdcc's assembly with the tag byte of generic pointers to RAM objects
    made RAM's (0x80) in data directives."""
    def line(text: str) -> str:
        if not text.lstrip().startswith("DB"):
            return text
        return _UPPER.sub(lambda m: "0x80" if m.group(1) in in_ram else m.group(0), text)
    return "\n".join(line(t) for t in asm.split("\n"))
