"""Prints the PT100 resistance table of generator/stdlib/actors/pt100_linearize.c.

Callendar-Van Dusen (IEC 60751), R0 = 100 ohm, every 10 degC from -200 to
850 degC, in 0.01 ohm. Run it to check or regenerate the table.
"""

A, B, C = 3.9083e-3, -5.775e-7, -4.183e-12


def resistance(t: float) -> float:
    """PT100 resistance in ohm at t degC."""
    r = 1 + A * t + B * t * t
    if t < 0:
        r += C * (t - 100) * t ** 3
    return 100 * r


def table() -> list[int]:
    """The table in 0.01 ohm."""
    return [round(resistance(t) * 100) for t in range(-200, 851, 10)]


if __name__ == "__main__":
    values = table()
    for i in range(0, len(values), 8):
        print("    " + ", ".join(f"{v}u" for v in values[i:i + 8]) + ",")
