"""C as the backend writes it: identifiers, literals, type limits and
IR expressions (docs/ir.md, "expressions"). Shared by every generator of C
(model.c, the interfaces' tables, boards' device tables)."""

from __future__ import annotations

import re

from ..core import expr as I
from ..core import types as T

C_TYPE_ENUM = {"bool": "EL_T_BOOL", "int8": "EL_T_I8", "uint8": "EL_T_U8", "int16": "EL_T_I16",
                "uint16": "EL_T_U16", "int32": "EL_T_I32", "uint32": "EL_T_U32", "float32": "EL_T_F32",
                "time": "EL_T_TIME"}
C_KIND_ENUM = {"param": "EL_K_PARAM", "var": "EL_K_VAR", "dev_out": "EL_K_DEV_OUT", "dev_in": "EL_K_DEV_IN"}
_UNSIGNED = {"int8": "uint8_t", "int16": "uint16_t", "int32": "uint32_t", "uint8": "uint8_t",
             "uint16": "uint16_t", "uint32": "uint32_t"}
_DIV_SUFFIX = {"int8": "i8", "int16": "i16", "int32": "i32", "uint8": "u8", "uint16": "u16",
               "uint32": "u32", "float32": "f32"}



def c_string(text: str) -> str:
    """``text`` as a C string literal whose bytes are its UTF-8: printable
    ASCII as is, but '\\', '"' and '?' escaped (no trigraph such as '??/'
    can form), every other byte an octal escape (no control, bidi or
    non-ASCII character reaches the C source). Every model string written
    into C as a literal goes through here (docs/language.md, "Strings in
    the generated C")."""
    out = []
    for ch in text:
        if ch in '\\"?':
            out.append("\\" + ch)
        elif " " <= ch <= "~":
            out.append(ch)
        else:
            out.append("".join(f"\\{b:03o}" for b in ch.encode("utf-8", "surrogatepass")))
    return '"' + "".join(out) + '"'


def c_comment(text) -> str:
    """``text`` made safe inside a C block comment: printable ASCII as is,
    except that no '*/' (which would end the comment), '/*' (-Wcomment) or
    '??' (a trigraph) can form; every other character as a \\u escape.
    Every model string written into a C comment (titles, file names of
    locations) goes through here; a value that is no string is shown by str()."""
    out = []
    for ch in str(text):
        if ch == "\\":
            out.append("\\\\")
        elif " " <= ch <= "~":
            # A '\\' after '*', '/' or '?' keeps '*/', '/*' and '??' apart.
            if out and out[-1][-1:] + ch in ("*/", "/*", "??"):
                out.append("\\")
            out.append(ch)
        else:
            out.append(f"\\u{ord(ch):04x}" if ord(ch) <= 0xFFFF else f"\\U{ord(ch):08x}")
    return "".join(out)


def ident(text: str) -> str:
    """A C identifier fragment from a model path."""
    return re.sub(r"[^A-Za-z0-9_]", "_", text)


def c_literal(t: T.ValueType, value) -> str:
    """A C constant of type ``t`` (run-time units: time in ms)."""
    if t is T.BOOL:
        return "true" if value else "false"
    if t is T.FLOAT32:
        text = repr(float(value))
        if "e" not in text and "." not in text and "inf" not in text:
            text += ".0"
        return f"{text}f"
    if t is T.STRING:
        return c_string(str(value))
    value = int(value)
    if t is T.TIME:
        return f"((el_time_t){value}u)"
    if t.signed and t.bits == 32 and value == t.min:
        return "((int32_t)(-2147483647L - 1L))"
    suffix = ("L" if t.signed else "UL") if t.bits == 32 else ("" if t.signed else "u")
    return f"(({t.c_name}){value}{suffix})"


def _operand(t: T.ValueType) -> str:
    """The el_wide.h operand suffix that takes a value of ``t``."""
    return "U" if t is T.UINT32 else "I"


def type_param_macros(name: str, t: T.ValueType, bindings: dict[str, T.ValueType]) -> list[tuple[str, str]]:
    """The macros actor code sees for a type parameter ``name`` bound to
    ``t`` (docs/language.md, "Inline C convention"): the type, its limits,
    its wide type and the accumulator operations on it (runtime_c/el_wide.h:
    int64_t where the compiler has one, software words where it does not),
    saturation back into the type, and the conversion of a value of each
    other type parameter of ``bindings`` into this one's wide type."""
    c = t.c_name
    if t is T.FLOAT32:
        lo, hi = "(-FLT_MAX)", "FLT_MAX"
        ops = {op: f"((w) {sym}= (float)(v))" for op, sym in (("ADD", "+"), ("SUB", "-"), ("MUL", "*"), ("DIV", "/"))}
        macros = [(f"{name}_WIDE", "float"), (f"{name}_W(w, v)", "((w) = (float)(v))")]
        macros += [(f"{name}_W{op}(w, v)", text) for op, text in ops.items()]
        macros += [(f"{name}_W{op}_I(w, v)", text) for op, text in ops.items()]
        macros += [(f"{name}_SAT(w)", f"(({c})el_clamp_f32((float)(w), {lo}, {hi}))"),
                   (f"{name}_NARROW(w)", f"(({c})(w))"),
                   (f"{name}_LIMIT(v, lo, hi)", f"(({c})el_clamp_f32((float)(v), (float)(lo), (float)(hi)))")]
    else:
        lo, hi = ("0", "1") if t is T.BOOL else (c_literal(t, t.min), c_literal(t, t.max))
        k = _operand(t)
        sat = f"(({c})EL_W_SAT_{'U32' if k == 'U' else 'I32'}(w, {lo}, {hi}))"
        clamp = "el_clamp_u32" if k == "U" else "el_clamp_i32"
        wide = "uint32_t" if k == "U" else "int32_t"
        macros = [(f"{name}_WIDE", "el_wide_t"), (f"{name}_W(w, v)", f"EL_W_SET_{k}(w, v)")]
        macros += [(f"{name}_W{op}(w, v)", f"EL_W_{op}_{k}(w, v)") for op in ("ADD", "SUB", "MUL", "DIV")]
        macros += [(f"{name}_W{op}_I(w, v)", f"EL_W_{op}_I(w, v)") for op in ("ADD", "SUB", "MUL", "DIV")]
        narrow = f"(({c})EL_W_NARROW_{'U32' if k == 'U' else 'I32'}(w))"
        macros += [(f"{name}_SAT(w)", sat), (f"{name}_NARROW(w)", narrow),
                   (f"{name}_LIMIT(v, lo, hi)", f"(({c}){clamp}(({wide})(v), ({wide})(lo), ({wide})(hi)))")]
    for other, u in bindings.items():
        if other == name:
            continue
        if t is T.FLOAT32:
            conv = "((w) = (float)(v))"
        elif u is T.FLOAT32:
            conv = "EL_W_SET_F(w, v)"
        else:
            conv = f"EL_W_SET_{_operand(u)}(w, v)"
        macros.append((f"{name}_W_{other}(w, v)", conv))
    return [(name, c), (f"{name}_MIN", lo), (f"{name}_MAX", hi), (f"{name}_BITS", str(t.bits)), *macros]


# ====================================================================== expressions


class ExprWriter:
    """Writes IR expressions as C, given how to name a referenced item."""

    def __init__(self, item_ref, step_time_ref=None, step_active_ref=None):
        self.item_ref = item_ref
        self.step_time_ref = step_time_ref
        self.step_active_ref = step_active_ref

    def write(self, e: I.IExpr) -> str:
        if isinstance(e, I.Const):
            return c_literal(e.type, e.value)
        if isinstance(e, I.Ref):
            if e.kind == "item":
                return self.item_ref(e)
            if e.kind == "step_time":
                return self.step_time_ref(e)
            return self.step_active_ref(e)
        if isinstance(e, I.Convert):
            return f"(({e.type.c_name}){self.write(e.arg)})"
        if isinstance(e, I.Unary):
            if e.op == "not":
                return f"(!{self.write(e.arg)})"
            if e.type is T.FLOAT32:
                return f"(-{self.write(e.arg)})"
            return f"EL_WRAP_NEG({e.type.c_name}, {_UNSIGNED[e.type.name]}, {self.write(e.arg)})"
        assert isinstance(e, I.Binary)
        a, b = self.write(e.left), self.write(e.right)
        op, t = e.op, e.operand_type
        if op == "and":
            return f"({a} && {b})"
        if op == "or":
            return f"({a} || {b})"
        if op in ("==", "!=", "<", "<=", ">", ">="):
            if t.is_integer:  # through el_cmp_*: no warning for comparisons the types decide
                return f"(el_cmp_{_DIV_SUFFIX.get(t.name, 'u32')}({a}, {b}) {op} 0)"
            return f"({a} {op} {b})"
        if t is T.TIME:
            return f"el_time_{'add' if op == '+' else 'sub'}({a}, {b})"
        if t is T.FLOAT32:
            return f"el_div_f32({a}, {b})" if op == "/" else f"({a} {op} {b})"
        if op in ("/", "%"):
            return f"el_{'div' if op == '/' else 'mod'}_{_DIV_SUFFIX[t.name]}({a}, {b})"
        macro = {"+": "EL_WRAP_ADD", "-": "EL_WRAP_SUB", "*": "EL_WRAP_MUL"}[op]
        return f"{macro}({t.c_name}, {_UNSIGNED[t.name]}, {a}, {b})"
