"""The rules of params, vars, channels and their delays (docs/language.md)."""

from __future__ import annotations

from fractions import Fraction

from ...core.source import note
from ...core import types as T
from .. import ast
from ..model import ChannelInfo, DataInfo
from .base import show_value, whole_ms


class DataRules:
    def check_data(self, decl: ast.Data) -> None:
        t = self.resolve_type(decl.type)
        if t is None:
            return
        if decl.type.size is not None:
            self.error(decl.type.span, f"a {decl.kind} is a scalar; arrays are for actor state only")
            return
        typer = self.const_typer()
        initial = 0 if t is not T.BOOL else False
        if t in (T.FLOAT32, T.TIME):
            initial = Fraction(0)
        if decl.default is not None:
            v = typer.expect_const(decl.default, t, f"the initial value of {decl.kind} '{decl.name}'")
            if v.type is not None:
                initial = v.const
        rng = None
        if decl.range is not None:
            if t is T.BOOL:
                self.error(decl.range.span, f"a range needs a number or time, and '{decl.name}' is a bool")
            else:
                lo = typer.expect_const(decl.range.low, t, "the range's lower bound")
                hi = typer.expect_const(decl.range.high, t, "the range's upper bound")
                if lo.type is not None and hi.type is not None:
                    rng = (lo.const, hi.const)
                    if lo.const > hi.const:
                        self.error(decl.range.span, f"empty range: {show_value(lo.const, t)} is above {show_value(hi.const, t)}")
                    elif not lo.const <= initial <= hi.const:
                        span = decl.default.span if decl.default is not None else decl.name_span
                        self.error(span, f"the initial value {show_value(initial, t)} of '{decl.name}' is outside "
                                         f"its range {show_value(lo.const, t)}..{show_value(hi.const, t)}",
                                   None if decl.default is not None else "give an initial value inside the range")
        if decl.scale is not None:
            self.check_scale(decl, t)
        if t is T.TIME and not whole_ms(initial):
            self.error(decl.default.span, "a run-time 'time' value counts whole milliseconds")
        if decl.persist and decl.kind != "param":
            span = dict(decl.attr_spans).get("persist", decl.span)
            self.error(span, "only params can be 'persist'", "make it a param, or drop 'persist'")
        if decl.service is not None and decl.service.address is not None and not 0 <= decl.service.address <= 65535:
            self.error(decl.service.span, f"register address {decl.service.address} is outside 0..65535")
        elif decl.service is not None and decl.service.address is not None:
            # Items clash when their registers overlap in the same table.
            table = T.register_table(t, decl.service.access)
            first = decl.service.address
            last = first + T.register_count(t) - 1
            for (other_table, other_first, other_last), other in self._addresses.items():
                if other_table == table and first <= other_last and other_first <= last:
                    where = f"{first}" if first == last else f"{first}..{last}"
                    self.error(decl.service.span, f"{table} register {where} of '{decl.name}' overlaps "
                                                  f"'{other.name}' ({other_first}..{other_last})"
                                                  if other_last != other_first or first != last else
                               f"{table} register {first} is given to '{other.name}' and to '{decl.name}'",
                               "give each item its own address, or leave the address out to have one assigned",
                               [note(other.service.span, f"'{other.name}' has it here")])
                    break
            else:
                self._addresses[(table, first, last)] = decl
        self.data[decl.name] = DataInfo(decl, t, initial, rng)

    def check_scale(self, decl: ast.Data, t: T.ValueType) -> None:
        """``scale``: a decimal within SCALE_MIN..SCALE_MAX of at most
        SCALE_DECIMALS decimals (so at most 15 significant digits: exact as a
        JSON number), on an integer item (engineering value = value x scale)."""
        span = dict(decl.attr_spans).get("scale", decl.span)
        if t not in T.INTEGERS:
            self.error(span, f"a scale needs an integer type, and '{decl.name}' is a {t.name}",
                       "drop 'scale', or store the value as an integer (int16 ... scale 0.1)")
        elif not T.SCALE_MIN <= decl.scale <= T.SCALE_MAX:
            self.error(span, f"the scale of '{decl.name}' is {T.show_real(decl.scale)}, outside "
                             f"{T.decimal_text(T.SCALE_MIN)}..{T.decimal_text(T.SCALE_MAX)}")
        elif T.decimal_text(decl.scale) is None:
            self.error(span, f"the scale of '{decl.name}' has more than {T.SCALE_DECIMALS} decimals",
                       "give a scale such as 0.1, 0.001 or 2.5")

    def check_channel(self, decl: ast.Channel) -> None:
        t = self.resolve_type(decl.type)
        if t is None:
            return
        tokens = self.delay_tokens(decl.delay, t) if decl.delay else ()
        self.channels[decl.name] = ChannelInfo(decl, t, tokens)

    def delay_tokens(self, delay: ast.Delay, t: T.ValueType) -> tuple:
        """The initial tokens a ``delay`` gives: a count of zeros, or a list."""
        typer = self.const_typer()
        if delay.values is not None:
            values = []
            for e in delay.values:
                v = typer.expect_const(e, t, "an initial token")
                values.append(v.const if v.type is not None else 0)
            return tuple(values)
        v = typer.expect_const(delay.count, None, "a delay")
        if v.type is None:
            return ()
        if not (v.type.is_integer and v.type is not T.TIME) or v.const < 0:
            self.error(delay.count.span, "a delay is a count of initial tokens: a non-negative integer",
                       "for initial values other than zero, write a list: delay [1, 2]")
            return ()
        if v.const > 1_000_000:
            self.error(delay.count.span, f"a delay of {v.const} tokens is more than this tool supports (1000000)")
            return ()
        zero = False if t is T.BOOL else 0
        return (zero,) * v.const

