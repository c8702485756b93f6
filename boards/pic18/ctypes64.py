"""C types as sdcc's pic16 port sees them, for lowering 64-bit integers
(lower64.py): the types of declarations and of expressions in a
translation unit parsed by pycparser.

Sizes are the target's (`Target`): for sdcc's pic16 port char 8 bits
(unsigned unless signed), short and int 16, long 32, long long 64 (which
the port lacks: lower64 turns them into calls), float and double 32; the
lowering's own tests run it with gcc's sizes. Only what the lowering needs
is modelled:
integer width and signedness, floats, pointers, arrays, structs and unions
(their members), functions (their return and parameter types).
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pycparser import c_ast


class LowerError(Exception):
    """A construct the lowering cannot express for sdcc (with where it is)."""


def const_value(e: c_ast.Node) -> int:
    """The value of an integer constant expression (array sizes, static
    initializers), computed without regard to types."""
    if isinstance(e, c_ast.Constant) and e.type not in ("string", "float", "double"):
        if e.type == "char":
            return ord(e.value.strip("'")[-1])
        text = e.value.lower().rstrip("ul")
        return int(text, 16) if text.startswith("0x") else int(text, 8) if len(text) > 1 and text[0] == "0" \
            else int(text)
    if isinstance(e, c_ast.Cast):
        return const_value(e.expr)
    if isinstance(e, c_ast.UnaryOp) and e.op in ("-", "+", "~"):
        v = const_value(e.expr)
        return {"-": -v, "+": v, "~": ~v}[e.op]
    if isinstance(e, c_ast.BinaryOp) and e.op in ("+", "-", "*", "/", "%", "<<", ">>", "&", "|", "^"):
        a, b = const_value(e.left), const_value(e.right)
        if e.op in ("/", "%") and b == 0:
            raise LowerError(f"{where(e)}division by zero in a constant expression")
        return {"+": a + b, "-": a - b, "*": a * b, "/": int(a / b) if b else 0, "%": a - b * int(a / b) if b else 0,
                "<<": a << b, ">>": a >> b, "&": a & b, "|": a | b, "^": a ^ b}[e.op]
    raise LowerError(f"{where(e)}not an integer constant the lowering can compute")


def where(node: c_ast.Node | None) -> str:
    coord = getattr(node, "coord", None)
    if coord is None or not getattr(coord, "file", None):
        return ""
    return f"{coord.file}:{coord.line}: "


@dataclass(frozen=True)
class CType:
    kind: str  # "int", "float", "void", "ptr", "array", "struct", "func"
    bits: int = 0  # int: 1 (_Bool), 8, 16, 32, 64
    signed: bool = True
    to: CType | None = None  # ptr, array: the element; func: the return type
    tag: str = ""  # struct/union: its tag or a unique name
    params: tuple = ()  # func: parameter types (None for `...`)
    count: int | None = None  # array: its length (None: unknown)

    @property
    def is_int(self) -> bool:
        return self.kind == "int"

    @property
    def wide(self) -> bool:
        """A 64-bit integer: what the lowering rewrites."""
        return self.kind == "int" and self.bits == 64

    @property
    def arithmetic(self) -> bool:
        return self.kind in ("int", "float")


VOID = CType("void")
BOOL = CType("int", 1, False)
INT = CType("int", 16, True)
I64 = CType("int", 64, True)
U64 = CType("int", 64, False)
FLOAT = CType("float", 32)
UNKNOWN = CType("int", 16, True)  # what an undeclared name is taken for (the compiler will say more)


@dataclass(frozen=True)
class Target:
    """A compiler's integer sizes."""

    int_bits: int = 16
    long_bits: int = 32
    char_signed: bool = False
    pointer_bytes: int = 3  # sdcc's generic pointers: 16-bit address and a memory space tag

    def int_type(self, names: list[str]) -> CType:
        """The type of a list of type specifiers (unsigned long long, char, ...)."""
        words = [n for n in names if n not in ("const", "volatile")]
        if "void" in words:
            return VOID
        if "float" in words or "double" in words:
            return FLOAT
        if "_Bool" in words:
            return BOOL
        unsigned = "unsigned" in words
        if "char" in words:
            return CType("int", 8, "signed" in words or (self.char_signed and not unsigned))
        longs = words.count("long")
        bits = 64 if longs >= 2 else self.long_bits if longs == 1 else 16 if "short" in words else self.int_bits
        return CType("int", bits, not unsigned)

    def promote(self, t: CType) -> CType:
        """Integer promotion."""
        if t.kind != "int" or t.bits >= self.int_bits:
            return t
        return CType("int", self.int_bits, True)

    def arithmetic_result(self, a: CType, b: CType) -> CType:
        """The usual arithmetic conversions of a binary operator."""
        if a.kind == "float" or b.kind == "float":
            return FLOAT
        a, b = self.promote(a), self.promote(b)
        if a.kind != "int" or b.kind != "int":  # pointer arithmetic and the like: not wide
            return a if a.kind != "int" else b
        if a.bits == b.bits:
            return CType("int", a.bits, a.signed and b.signed)
        wider = a if a.bits > b.bits else b
        return CType("int", wider.bits, wider.signed)  # it represents every value of the narrower


@dataclass
class Scope:
    names: dict[str, CType] = field(default_factory=dict)
    parent: Scope | None = None

    def lookup(self, name: str) -> CType | None:
        s: Scope | None = self
        while s is not None:
            if name in s.names:
                return s.names[name]
            s = s.parent
        return None


class TypeEnv:
    """Typedefs, struct and union members, and scopes of names."""

    def __init__(self, target: Target):
        self.target = target
        self.typedefs: dict[str, CType] = {}
        self.members: dict[str, dict[str, CType]] = {}
        self.enums: set[str] = set()
        self.scope = Scope()
        self._anon: dict[int, str] = {}
        self.record_bytes: dict[str, int] = {}

    # ---- scopes

    def push(self) -> None:
        self.scope = Scope(parent=self.scope)

    def pop(self) -> None:
        assert self.scope.parent is not None
        self.scope = self.scope.parent

    def declare(self, name: str, t: CType) -> None:
        self.scope.names[name] = t

    def lookup(self, name: str) -> CType:
        t = self.scope.lookup(name)
        if t is not None:
            return t
        return CType("int", self.target.int_bits, True) if name in self.enums else UNKNOWN

    # ---- declarations

    def of_decl(self, node: c_ast.Node) -> CType:
        """The type a declarator or type name describes."""
        if isinstance(node, (c_ast.Decl, c_ast.Typename)):
            return self.of_decl(node.type)
        if isinstance(node, c_ast.TypeDecl):
            return self.of_decl(node.type)
        if isinstance(node, c_ast.PtrDecl):
            return CType("ptr", to=self.of_decl(node.type))
        if isinstance(node, c_ast.ArrayDecl):
            try:
                count = const_value(node.dim) if node.dim is not None else None
            except LowerError:
                count = None
            return CType("array", to=self.of_decl(node.type), count=count)
        if isinstance(node, c_ast.FuncDecl):
            params = []
            for p in (node.args.params if node.args else []):
                if isinstance(p, c_ast.EllipsisParam):
                    params.append(None)
                elif isinstance(p, c_ast.ID):  # K&R identifier list
                    params.append(INT)
                else:
                    pt = self.of_decl(p)
                    if pt.kind != "void":
                        params.append(pt if pt.kind != "array" else CType("ptr", to=pt.to))
            return CType("func", to=self.of_decl(node.type), params=tuple(params))
        if isinstance(node, c_ast.IdentifierType):
            if len(node.names) == 1 and node.names[0] in self.typedefs:
                return self.typedefs[node.names[0]]
            return self.target.int_type(node.names)
        if isinstance(node, (c_ast.Struct, c_ast.Union)):
            return self.record(node)
        if isinstance(node, c_ast.Enum):
            if node.values is not None:
                for e in node.values.enumerators:
                    self.enums.add(e.name)
            return CType("int", self.target.int_bits, True)
        raise LowerError(f"{where(node)}unexpected declarator {type(node).__name__}")

    def record(self, node: c_ast.Struct | c_ast.Union) -> CType:
        """A struct or union: its members are remembered under its tag."""
        tag = node.name or self._anon.setdefault(id(node), f"<anonymous {len(self._anon) + 1}>")
        if node.decls is not None:
            fields: dict[str, CType] = {}
            sizes = []
            for d in node.decls:
                inner = self.of_decl(d.type)
                sizes.append(self.size(inner))
                if d.name is not None:
                    fields[d.name] = inner
                else:  # an anonymous struct or union member: its members are ours
                    fields.update(self.members.get(inner.tag, {}))
            self.members[tag] = fields
            known = [n for n in sizes if n is not None]
            if len(known) == len(sizes):  # sdcc does not pad on these 8-bit parts
                self.record_bytes[tag] = max(known, default=0) if isinstance(node, c_ast.Union) else sum(known)
        return CType("struct", tag=tag)

    def size(self, t: CType) -> int | None:
        """sizeof on the target (None when unknown)."""
        if t.kind == "int":
            return max(1, t.bits // 8)
        if t.kind == "float":
            return 4
        if t.kind == "ptr":
            return self.target.pointer_bytes
        if t.kind == "array":
            inner = self.size(t.to) if t.to is not None else None
            return inner * t.count if inner is not None and t.count is not None else None
        if t.kind == "struct":
            return self.record_bytes.get(t.tag)
        return None

    def member(self, record: CType, name: str, node: c_ast.Node) -> CType:
        if record.kind != "struct":
            raise LowerError(f"{where(node)}member '{name}' of something that is no struct")
        fields = self.members.get(record.tag)
        if fields is None or name not in fields:
            return UNKNOWN
        return fields[name]

    def typedef(self, decl: c_ast.Typedef) -> None:
        self.typedefs[decl.name] = self.of_decl(decl.type)


def each_function(ast: c_ast.FileAST, env: TypeEnv, visit) -> None:
    """Walk a unit's top level with ``env``: typedefs and declarations go
    into it, and each function definition is handed to ``visit(def, its
    type)`` with its parameters declared in a scope of their own."""
    for ext in ast.ext:
        if isinstance(ext, c_ast.Typedef):
            env.typedef(ext)
        elif isinstance(ext, c_ast.Decl):
            t = env.of_decl(ext.type)
            if ext.name:
                env.declare(ext.name, t)
        elif isinstance(ext, c_ast.FuncDef):
            t = env.of_decl(ext.decl.type)
            env.declare(ext.decl.name, t)
            env.push()
            for p in (ext.decl.type.args.params if ext.decl.type.args else []):
                if isinstance(p, c_ast.Decl) and p.name:
                    env.declare(p.name, env.of_decl(p.type))
            visit(ext, t)
            env.pop()


class BottomUpRewriter(c_ast.NodeVisitor):
    """Replaces expressions in a unit's function bodies, children first:
    a subclass's ``rewrite`` returns a node or what stands for it (and
    counts it in ``count``)."""

    def __init__(self):
        self.count = 0

    def rewrite(self, node: c_ast.Node) -> c_ast.Node:
        return node

    def generic_visit(self, node: c_ast.Node) -> None:
        for name, child in node.children():
            self.visit(child)
            base = name.split("[")[0]
            if "[" in name:
                items = list(getattr(node, base))
                k = int(name.split("[")[1].rstrip("]"))
                items[k] = self.rewrite(items[k])
                setattr(node, base, items)
            else:
                setattr(node, base, self.rewrite(getattr(node, base)))

    def run(self, ast: c_ast.FileAST) -> int:
        """Rewrite every function body of the unit in place; how many nodes were replaced."""
        for ext in ast.ext:
            if isinstance(ext, c_ast.FuncDef):
                self.visit(ext.body)
        return self.count


def pure(e: c_ast.Node) -> bool:
    """Evaluating it twice is the same as once (no calls, no assignments)."""
    if isinstance(e, (c_ast.FuncCall, c_ast.Assignment)):
        return False
    if isinstance(e, c_ast.UnaryOp) and e.op in ("++", "--", "p++", "p--"):
        return False
    return all(pure(child) for _, child in e.children())
