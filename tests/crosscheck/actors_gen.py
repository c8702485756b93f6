"""The actors of random models: every std actor type with each type
parameter it accepts and boundary arguments, and user actor types written
for the model (integer arithmetic of every width, rates, state).

An actor is described by what the dataflow generator needs: the instance's
declaration, its inputs (port, type, rate) and its outputs (port, type,
rate). Rates are tokens per firing; the dataflow generator keeps them
consistent."""

from __future__ import annotations

import random
from dataclasses import dataclass, field

from ctypes_gen import INT_NAMES, ExprWriter, boundary, model_literal, widens

COMPARE_OPS = ["<", "<=", ">", ">=", "==", "!="]


@dataclass
class Port:
    name: str
    type: str
    rate: int = 1


@dataclass
class ActorUse:
    """One instance to declare: ``decl`` is ``Type<..>(args)``."""

    decl: str
    inputs: list[Port]
    outputs: list[Port]


@dataclass
class UserType:
    """A user actor type of the model."""

    name: str
    params: list[tuple[str, str, int]]  # name, type, default
    inputs: list[Port]
    outputs: list[Port]
    text: str = ""


@dataclass
class Catalog:
    """Chooses actors for a model; ``numeric`` are the types a ``T:
    number`` parameter may take (float32 among them when asked), ``params``
    the model's params (name -> type) that arguments may use."""

    rng: random.Random
    numeric: list[str]
    params: dict[str, str] = field(default_factory=dict)
    user_types: list[UserType] = field(default_factory=list)

    # ------------------------------------------------------------ arguments

    def arg(self, t: str, *, lo=None, hi=None, allow_param: bool = True) -> str:
        """A compile-time argument of type ``t``: a boundary constant, or a
        param of a type that widens to ``t`` (latched at each release)."""
        rng = self.rng
        usable = [n for n, pt in self.params.items() if widens(pt, t)] if allow_param else []
        if usable and rng.random() < 0.2 and lo is None:
            return rng.choice(usable)
        if lo is not None:
            return str(rng.randint(lo, hi))
        return model_literal(t, boundary(rng, t))

    def integer(self) -> str:
        return self.rng.choice(INT_NAMES)

    def number(self) -> str:
        return self.rng.choice(self.numeric)

    # ------------------------------------------------------------ std actors

    def std(self, kind: str, want_in: str | None = None) -> ActorUse:
        """An instance of the std actor ``kind``; ``want_in``: the type of
        the input it will be fed (chosen by the caller), if any."""
        rng = self.rng
        t = want_in or self.number()
        if kind == "Const":
            return ActorUse(f"Const<{t}>(value = {self.arg(t)})", [], [Port("y", t)])
        if kind == "Ramp":
            return ActorUse(f"Ramp<{t}>(slope = {self.arg(t)})", [], [Port("y", t)])
        if kind == "SquareWave":
            hp = rng.choice([0, 1, 2, 3, 5, 65535, rng.randint(1, 20)])
            return ActorUse(f"SquareWave(half_period = {hp})", [], [Port("y", "bool")])
        if kind in ("Add", "Sub", "Mul", "Div"):
            return ActorUse(f"{kind}<{t}>()", [Port("a", t), Port("b", t)], [Port("y", t)])
        if kind in ("Gain", "Integrator", "Differentiator"):
            return ActorUse(f"{kind}<{t}>(k = {self.arg('int32')})", [Port("x", t)], [Port("y", t)])
        if kind == "LowPass":
            return ActorUse(f"LowPass<{t}>(alpha = {self.arg('int16')})", [Port("x", t)], [Port("y", t)])
        if kind == "Limit":
            a, b = sorted([boundary(rng, t), boundary(rng, t)])
            return ActorUse(f"Limit<{t}>(min = {model_literal(t, a)}, max = {model_literal(t, b)})",
                            [Port("x", t)], [Port("y", t)])
        if kind == "Cast":
            b = self.number()
            return ActorUse(f"Cast<{t}, {b}>()", [Port("x", t)], [Port("y", b)])
        if kind == "Linear":
            return ActorUse(f"Linear(gain = {self.arg('int16')}, offset = {self.arg('int16')})",
                            [Port("x", "int16")], [Port("y", "int16")])
        if kind == "Select":
            return ActorUse(f"Select<{t}>()", [Port("sel", "bool"), Port("a", t), Port("b", t)], [Port("y", t)])
        if kind == "Compare":
            op = rng.choice(COMPARE_OPS)
            return ActorUse(f'Compare<{t}>(op = "{op}", threshold = {self.arg(t)})', [Port("x", t)],
                            [Port("y", "bool")])
        if kind == "Hysteresis":
            return ActorUse(f"Hysteresis<{t}>(on_above = {self.arg(t)}, off_below = {self.arg(t)})",
                            [Port("x", t)], [Port("y", "bool")])
        if kind == "Counter":
            return ActorUse("Counter()", [Port("x", "bool")], [Port("y", "uint32")])
        if kind == "PID":
            lo, hi = sorted([boundary(rng, t), boundary(rng, t)])
            gains = ", ".join(f"{g} = {self.arg('int32')}" for g in ("kp", "ki", "kd"))
            return ActorUse(f"PID<{t}>({gains}, out_min = {lo}, out_max = {hi})",
                            [Port("setpoint", t), Port("measured", t)], [Port("y", t)])
        if kind == "MovingAverage":
            n = rng.choice([1, 2, 3, 8, 8, 200])
            return ActorUse(f"MovingAverage<{t}>(n = {n})", [Port("x", t)], [Port("y", t)])
        if kind == "Pt100Linearize":
            return ActorUse("Pt100Linearize()", [Port("x", "uint16")], [Port("y", "int16")])
        raise ValueError(kind)

    def multirate(self, kind: str, t: str, factor: int) -> ActorUse:
        """Downsample, Upsample or WindowStats of ``factor`` tokens."""
        if kind == "Downsample":
            return ActorUse(f"Downsample<{t}>(factor = {factor})", [Port("x", t, factor)], [Port("y", t)])
        if kind == "Upsample":
            return ActorUse(f"Upsample<{t}>(factor = {factor})", [Port("x", t)], [Port("y", t, factor)])
        return ActorUse(f"WindowStats<{t}>(n = {factor})", [Port("x", t, factor)],
                        [Port("min", t), Port("max", t), Port("mean", t)])

    # ------------------------------------------------------------ user actor types

    def user_type(self, index: int) -> UserType:
        """A new user actor type: 1-2 inputs and 1-2 outputs of random
        integer types (bool now and then), rates 1-3, 0-2 parameters,
        0-2 state variables, and a step of random arithmetic."""
        rng = self.rng
        name = f"U{index}"
        params = [(f"k{i}", self.integer(), 0) for i in range(rng.randint(0, 2))]
        params = [(n, t, boundary(rng, t)) for n, t, _ in params]
        inputs = [Port(f"x{i}", rng.choice(INT_NAMES + ["bool"]), rng.choice([1, 1, 1, 2, 3]))
                  for i in range(rng.randint(1, 2))]
        outputs = [Port(f"y{i}", rng.choice(INT_NAMES + ["bool"]), rng.choice([1, 1, 1, 2, 3]))
                   for i in range(rng.randint(1, 2))]
        states = [(f"s{i}", self.integer()) for i in range(rng.randint(0, 2))]
        operands = {n: t for n, t, _ in params} | {n: t for n, t in states}
        for p in inputs:
            if p.rate == 1:
                operands[p.name] = p.type
            else:
                operands[f"{p.name}[0]"] = p.type
                operands[f"{p.name}[{p.rate - 1}]"] = p.type
        loops = any(p.rate > 1 for p in outputs)
        body = ["uint16_t i;"] if loops else []
        exprs = ExprWriter(rng, operands)
        for n, t in states:
            body.append(f"{n} = {exprs.of(t, 3)};")
        loop_operands = dict(operands, i="uint16")
        for p in outputs:
            if p.rate == 1:
                body.append(f"{p.name} = {exprs.of(p.type, 3)};")
            else:
                value = ExprWriter(rng, loop_operands).of(p.type, 3)
                body.append(f"for (i = 0u; i < {p.rate}u; i++) {{ {p.name}[i] = {value}; }}")
        lines = [f"actor type {name}(" + ", ".join(f"{n}: {t} = {model_literal(t, d)}" for n, t, d in params) + ") {"]
        lines += [f"    in  {p.name}: {p.type}" + (f" rate {p.rate}" if p.rate > 1 else "") for p in inputs]
        lines += [f"    out {p.name}: {p.type}" + (f" rate {p.rate}" if p.rate > 1 else "") for p in outputs]
        lines += [f"    state {n}: {t}" for n, t in states]
        lines += ["    step {{"] + [f"        {b}" for b in body] + ["    }}", "}"]
        ut = UserType(name, params, inputs, outputs, "\n".join(lines))
        self.user_types.append(ut)
        return ut

    def user(self) -> ActorUse:
        """An instance of one of the model's user types (a new one now and
        then), with boundary arguments or params."""
        rng = self.rng
        if not self.user_types or (len(self.user_types) < 3 and rng.random() < 0.4):
            self.user_type(len(self.user_types))
        ut = rng.choice(self.user_types)
        args = ", ".join(f"{n} = {self.arg(t)}" for n, t, _ in ut.params if rng.random() < 0.7)
        return ActorUse(f"{ut.name}({args})", [Port(p.name, p.type, p.rate) for p in ut.inputs],
                        [Port(p.name, p.type, p.rate) for p in ut.outputs])


STD_SINGLE_RATE = ["Const", "Ramp", "SquareWave", "Add", "Sub", "Mul", "Div", "Gain", "Integrator", "Differentiator",
                   "LowPass", "Limit", "Cast", "Linear", "Select", "Compare", "Hysteresis", "Counter", "PID",
                   "MovingAverage", "Pt100Linearize"]
INTEGER_ONLY = {"PID", "MovingAverage"}
MULTIRATE = ["Downsample", "Upsample", "WindowStats"]
