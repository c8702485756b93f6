"""Models of every std actor with compile-time arguments at their ends
(docs/stdlib.md): for each type a parameter of type T takes (int8 ..
uint32, float32) and each of 0, the type's minimum and its maximum, an
instance per actor; int32 gains at 0 and the int32 ends, sizes at their
smallest and largest. Generated, not picked: a comparison that such an
argument (or a type parameter: `a < 0` on an unsigned T) decides must
compile on every board (docs/language.md, "Actor code and compiler
warnings")."""

from __future__ import annotations

from easylab.core import types as T

NUMBERS = [T.INT8, T.UINT8, T.INT16, T.UINT16, T.INT32, T.UINT32, T.FLOAT32]
INTEGERS = [t for t in NUMBERS if t.is_integer]
OPS = ["<", "<=", ">", ">=", "==", "!="]
MAX_TASKS = 32  # a model's most (docs/language.md)


def ends(t: T.ValueType) -> list[int]:
    """0, the minimum and the maximum of ``t`` (float32: its finite range)."""
    if t is T.FLOAT32:
        return [0, -T.FLOAT32_MAX, T.FLOAT32_MAX]
    return sorted({0, t.min, t.max}, key=[0, t.min, t.max].index)


def lit(v: int) -> str:
    return f"({v})" if v < 0 else str(v)


def actors(t: T.ValueType, big: bool) -> list[tuple[str, dict[str, str]]]:
    """(instance declaration, {input port: type}) of every std actor of type
    parameter ``t`` at the ends of its arguments; ``big``: sizes at 65535
    too (rates of 65535 tokens: a host's memory, not an MCU's)."""
    n = t.name
    out: list[tuple[str, dict[str, str]]] = []
    ab = {"a": n, "b": n}
    x = {"x": n}
    for actor in ("Add", "Sub", "Mul", "Div"):
        out.append((f"{actor}<{n}>()", ab))
    out.append((f"Select<{n}>()", {"sel": "bool", "a": n, "b": n}))
    for v in ends(t):
        out.append((f"Const<{n}>(value = {lit(v)})", {}))
        out.append((f"Ramp<{n}>(slope = {lit(v)})", {}))
        out.append((f"Limit<{n}>(min = {lit(v)}, max = {lit(v)})", x))
        out.append((f"Hysteresis<{n}>(on_above = {lit(v)}, off_below = {lit(v)})", x))
        out += [(f'Compare<{n}>(op = "{op}", threshold = {lit(v)})', x) for op in OPS]
    for k in ends(T.INT32):
        out.append((f"Gain<{n}>(k = {lit(k)})", x))
        out.append((f"Integrator<{n}>(k = {lit(k)})", x))
        out.append((f"Differentiator<{n}>(k = {lit(k)})", x))
    for alpha in ends(T.INT16):
        out.append((f"LowPass<{n}>(alpha = {lit(alpha)})", x))
    if t.is_integer:
        for k, v in zip(ends(T.INT32), ends(t)):
            out.append((f"PID<{n}>(kp = {lit(k)}, ki = {lit(k)}, kd = {lit(k)}, out_min = {lit(v)}, "
                        f"out_max = {lit(v)})", {"setpoint": n, "measured": n}))
        out += [(f"MovingAverage<{n}>(n = {size})", x) for size in (1, 255)]
    for size in (1, 65535) if big else (1, 3):
        # multirate: an Upsample feeds a Downsample and a WindowStats of the same factor
        out.append((f"Upsample<{n}>(factor = {size})", x))
        out.append((f"Downsample<{n}>(factor = {size})", {"x": f"{n}*{size}"}))
        out.append((f"WindowStats<{n}>(n = {size})", {"x": f"{n}*{size}"}))
    return out


def model(name: str, types: list[T.ValueType], *, big: bool = False, casts: bool = True,
          others: bool = True, traced: bool = True, chunk: int = 12, only: set[str] | None = None) -> str:
    """A model with the actors of ``actors`` for each of ``types``, fed by
    Ramps of their types (to the maximum in 8 firings; an Upsample feeds
    the multirate ones), with ``casts``: Cast between every pair of numeric
    types, ``others``: the actors without a type parameter (SquareWave at
    0, 1 and 65535, Linear at the int16 ends, Counter, Pt100Linearize).
    With ``traced``, every output goes to a var (traced), else nowhere (an
    MCU's RAM holds the actors, not also a var per output). The actors come
    ``chunk`` (or more, for at most 32 tasks) to a dataflow, each run by a task of its own: sdcc's pic16
    port takes minutes over one function of hundreds of actors, and the
    PIC18 build writes a task's dataflows and actors into its function.
    ``only``: the actor types to keep (all when None)."""
    jobs: list[tuple[str, dict[str, str], list[tuple[str, str]], str]] = []  # decl, inputs, (port, type) out, T

    def outputs(decl: str, t: str) -> list[tuple[str, str]]:
        kind = decl.split("<")[0].split("(")[0]
        if kind in ("Compare", "Hysteresis", "SquareWave"):
            return [("y", "bool")]
        if kind == "WindowStats":
            return [(p, t) for p in ("min", "max", "mean")]
        if kind == "Upsample":  # its rate-n output goes to no var
            return []
        if kind == "Cast":
            return [("y", decl.split(",")[1].split(">")[0].strip())]
        if kind == "Counter":
            return [("y", "uint32")]
        if kind in ("Linear", "Pt100Linearize"):
            return [("y", "int16")]
        return [("y", t)]

    for t in types:
        jobs += [(decl, inputs, outputs(decl, t.name), t.name) for decl, inputs in actors(t, big)]
    if casts:
        jobs += [(f"Cast<{a.name}, {b.name}>()", {"x": a.name}, [("y", b.name)], a.name)
                 for a in NUMBERS for b in NUMBERS]
    if others:
        jobs += [(f"SquareWave(half_period = {half})", {}, [("y", "bool")], "") for half in (0, 1, 65535)]
        jobs += [(f"Linear(gain = {lit(g)}, offset = {lit(o)})", {"x": "int16"}, [("y", "int16")], "int16")
                 for g in ends(T.INT16) for o in ends(T.INT16)]
        jobs += [("Counter()", {"x": "bool"}, [("y", "uint32")], ""),
                 ("Pt100Linearize()", {"x": "uint16"}, [("y", "int16")], "")]
    if only is not None:
        jobs = [j for j in jobs if j[0].split("<")[0].split("(")[0] in only]
    chunk = max(chunk, -(-len(jobs) // MAX_TASKS))
    head = [f"model {name}", "import std", ""]
    tail: list[str] = []
    count = 0
    for c in range(0, len(jobs), chunk):
        body: list[str] = []
        sources: dict[str, str] = {}

        def source(typ: str) -> str:
            if typ not in sources:
                if typ == "bool":
                    body.append("    flag = SquareWave(half_period = 2)")
                    sources[typ] = "flag.y"
                elif "*" in typ:
                    t, size = typ.split("*")
                    body.append(f"    up_{t}_{size} = Upsample<{t}>(factor = {size})")
                    body.append(f"    {source(t)} -> up_{t}_{size}.x")
                    sources[typ] = f"up_{t}_{size}.y"
                else:
                    step = "1.0e37" if typ == "float32" else str(max(1, T.SCALARS[typ].max // 8))
                    body.append(f"    src_{typ} = Ramp<{typ}>(slope = {step})")
                    sources[typ] = f"src_{typ}.y"
            return sources[typ]

        for decl, inputs, outs, _ in jobs[c:c + chunk]:
            count += 1
            inst = f"a{count}"
            body.append(f"    {inst} = {decl}")
            for port, typ in inputs.items():
                body.append(f"    {source(typ)} -> {inst}.{port}")
            for port, typ in outs if traced else []:
                head.append(f"var o{count}_{port}: {typ}")
                body.append(f"    {inst}.{port} -> o{count}_{port}")
        k = c // chunk
        tail += ["", f"dataflow D{k} {{", *body, "}", f"task t{k} period 1 ms {{ run D{k} }}"]
    return "\n".join(head + tail) + "\n"
