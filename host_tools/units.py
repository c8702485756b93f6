"""Engineering units of the service and debug maps.

An integer item may carry a ``scale`` (docs/language.md, "Consts, params,
vars"): its engineering value is its stored value times the scale
(``temperature: int16 unit "degC" scale 0.1`` stores 1628 for 162.8 degC).
The maps carry the scale as a JSON number of at most 15 significant digits;
here it is an exact decimal, so showing a value and reading one typed by a
person never round: a value that is no whole multiple of the scale is
refused, not rounded. The panel's page (host_tools/web/static/panel.js)
follows the same rules with BigInt arithmetic.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from decimal import Decimal, InvalidOperation
from fractions import Fraction

# A decimal number as a person types it: no hex, no NaN, an exponent of at most 3 digits.
_DECIMAL = re.compile(r"[+-]?(\d+\.?\d*|\.\d+)([eE][+-]?\d{1,3})?")


class ScaleError(ValueError):
    """Text that is no value of a scaled item; the message is one line."""


@dataclass(frozen=True)
class Scale:
    """``digits / 10**decimals``, exact (``Scale(1, 1)`` is 0.1)."""

    digits: int = 1
    decimals: int = 0

    @classmethod
    def of(cls, number) -> "Scale":
        """The scale of a map's ``scale`` field (a JSON number or decimal
        text; None or absent: 1). ValueError when it is not positive."""
        if number is None:
            return cls()
        text = repr(number) if isinstance(number, float) else str(number)
        try:
            value = Decimal(text)
        except InvalidOperation:
            raise ValueError(f"scale {text!r} is not a number") from None
        if not value.is_finite() or value <= 0:
            raise ValueError(f"scale {text} is not a positive number")
        _, digits, exponent = value.normalize().as_tuple()
        whole = int("".join(map(str, digits)))
        if exponent >= 0:
            return cls(whole * 10 ** exponent, 0)
        return cls(whole, -exponent)

    @property
    def is_one(self) -> bool:
        return self.digits == 1 and self.decimals == 0

    @property
    def fraction(self) -> Fraction:
        return Fraction(self.digits, 10 ** self.decimals)

    def text(self) -> str:
        """The scale as plain decimal text ("0.1", "2.5", "10")."""
        return self.show(1)

    def show(self, stored: int) -> str:
        """The engineering value of a stored integer, with the scale's
        decimals (1628 at 0.1: "162.8"; 10 at 0.1: "1.0")."""
        n = int(stored) * self.digits
        if self.decimals == 0:
            return str(n)
        sign, text = ("-" if n < 0 else ""), str(abs(n)).rjust(self.decimals + 1, "0")
        return f"{sign}{text[:-self.decimals]}.{text[-self.decimals:]}"

    def value(self, stored: int) -> float:
        """The engineering value as a number (for plots and CSV columns)."""
        return float(self.show(stored))

    def stored(self, text: str) -> int:
        """The stored integer of an engineering value typed as text;
        ScaleError when it is not a decimal number or not a whole multiple
        of the scale (nothing is rounded)."""
        t = text.strip()
        if not _DECIMAL.fullmatch(t):
            raise ScaleError(f"'{text}' is not a decimal number")
        quotient = Fraction(Decimal(t)) / self.fraction
        if quotient.denominator != 1:
            raise ScaleError(f"{t} is not a multiple of the scale {self.text()}: it cannot be stored exactly")
        return quotient.numerator
