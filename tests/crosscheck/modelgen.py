"""Random models for back-to-back testing (docs/testing.md).

``generate(seed, part)`` writes a whole model and a stimulus from a seed,
reproducibly: params (ranges, persist), consts, vars, devices of every
std kind on the part's pins, dataflows of std and user actors (boundary
arguments, widening edges, multi-rate edges with delays and feedback),
channels between tasks, charts with parallel branches, timed guards and
actions, and several tasks with offsets and deadlines. The models are
written without looking at how any backend works: the generator knows the
language (docs/language.md) and the std library (docs/stdlib.md) only.
"""

from __future__ import annotations

import random
import re
from dataclasses import dataclass, field

from actors_gen import INTEGER_ONLY, MULTIRATE, STD_SINGLE_RATE, ActorUse, Catalog, Port
from ctypes_gen import INT_NAMES, INTS, boundary, model_literal, widens
from parts_gen import PARTS, Part
from charts_gen import chart_text

MAX_TOKENS = 6  # tokens per iteration a signal may carry


@dataclass
class Signal:
    ref: str
    type: str
    tokens: int  # per dataflow iteration
    actor: bool  # an actor output (edges from it may carry delays)
    order: int = 0


@dataclass
class Task:
    name: str
    period_ms: int
    offset_us: int
    deadline_us: int
    runs: list[str] = field(default_factory=list)


@dataclass
class GeneratedModel:
    name: str
    seed: int
    part: str
    text: str
    stimulus: str
    duration_ms: int


@dataclass
class Options:
    floats: bool = False
    widening: bool = True
    charts: bool = True
    channels: bool = True
    devices: bool = True
    max_actors: int = 9
    duration_ms: int = 120


class ModelWriter:
    """One random model; ``write()`` gives its text."""

    def __init__(self, seed: int, part: Part, options: Options) -> None:
        self.rng = random.Random(seed)
        self.seed = seed
        self.part = part
        self.opt = options
        self.params: dict[str, str] = {}
        self.param_ranges: dict[str, tuple] = {}
        self.vars: dict[str, str] = {}
        self.var_writer: dict[str, str] = {}  # var -> task
        self.consts: dict[str, str] = {}
        self.device_outs: dict[str, tuple[str, int, int]] = {}  # datum -> (type, lo, hi)
        self.device_ins: dict[str, str] = {}
        self.device_in_writer: dict[str, str] = {}
        self.decls: list[str] = []
        self.bodies: list[str] = []
        self.tasks: list[Task] = []
        self.channels: list[str] = []
        self.pending_channels: list[tuple[str, str, int, str]] = []  # produced, not yet consumed
        self.consumed: list[tuple[str, str]] = []  # channels declared: name, type
        self.head_lines: list[str] = []
        numeric = INT_NAMES + (["float32"] if options.floats else [])
        self.catalog = Catalog(self.rng, numeric, self.params)
        self.count = 0

    def fresh(self, prefix: str) -> str:
        self.count += 1
        return f"{prefix}{self.count}"

    # ------------------------------------------------------------ items

    def items(self) -> None:
        rng = self.rng
        for _ in range(rng.randint(1, 4)):
            t = rng.choice(INT_NAMES + ["bool"])
            name = self.fresh("p")
            v = boundary(rng, t)
            attrs = ""
            if t != "bool" and rng.random() < 0.5:
                lo, hi = sorted([boundary(rng, t), boundary(rng, t)])
                v = min(max(v, lo), hi)
                attrs += f" range {lo}..{hi}"
                self.param_ranges[name] = (lo, hi)
            if rng.random() < 0.4:
                attrs += " service rw"
            if rng.random() < 0.3:
                attrs += " persist"
            self.params[name] = t
            self.decls.append(f"param {name}: {t} = {model_literal(t, v)}{attrs}")
        for _ in range(rng.randint(0, 2)):
            t = rng.choice(INT_NAMES)
            name = self.fresh("K")
            self.consts[name] = t
            self.decls.append(f"const {name}: {t} = {boundary(rng, t)}")

    def new_var(self, t: str, task: str | None) -> str:
        name = self.fresh("v")
        self.vars[name] = t
        if task:
            self.var_writer[name] = task
        init = f" = {model_literal(t, boundary(self.rng, t))}" if self.rng.random() < 0.3 else ""
        self.decls.append(f"var {name}: {t}{init}" + (" service ro" if self.rng.random() < 0.2 else ""))
        return name

    def device(self, prefix: str, declaration: str, datum: str, t: str, bounds: tuple[int, int] | None = None,
               safe: str = "") -> None:
        """A device ``declaration`` (``Type(args)``) and its one datum: an
        ``out`` datum within ``bounds`` (what the stimulus may give), else
        an ``in`` datum."""
        d = self.fresh(prefix)
        self.decls.append(f"device {d}: {declaration}{safe}")
        if bounds is not None:
            self.device_outs[f"{d}.{datum}"] = (t, *bounds)
        else:
            self.device_ins[f"{d}.{datum}"] = t

    def devices(self) -> None:
        rng, part = self.rng, self.part
        if not self.opt.devices:
            return
        pins = list(part.digital)
        rng.shuffle(pins)
        for _ in range(rng.randint(0, 2)):
            if pins:
                self.device("din", f'DigitalIn(pin = "{pins.pop()}")', "level", "bool", (0, 1))
        for _ in range(rng.randint(0, 2)):
            if pins:
                safe = f" safe level = {rng.choice(['true', 'false'])}" if rng.random() < 0.3 else ""
                self.device("dout", f'DigitalOut(pin = "{pins.pop()}")', "level", "bool", safe=safe)
        channels = list(part.adc)
        rng.shuffle(channels)
        for _ in range(rng.randint(0, 2)):
            if channels:
                if rng.random() < 0.3:
                    self.device("adc", f"Pt100(channel = {channels.pop()})", "raw", "uint16", (0, part.adc_max))
                else:
                    self.device("adc", f"AnalogIn(channel = {channels.pop()})", "value", "uint16", (0, part.adc_max))
        pwms = list(part.pwm)
        rng.shuffle(pwms)
        if pwms and rng.random() < 0.5:
            self.device("pwm", f'PwmOut(pin = "{pwms.pop()}")', "duty", "int16")
        if pwms and pins and rng.random() < 0.4:
            self.device("motor", f'Motor(pwm = "{pwms.pop()}", dir = "{pins.pop()}")', "speed", "int16")
        if part.i2c and rng.random() < 0.3:
            self.device("temp", f"I2cTemperature(address = {rng.randint(0x48, 0x4F)})", "temperature", "int16",
                        (-880, 2047))
        if part.i2c and rng.random() < 0.2:
            self.device("log", f"I2cEepromLog(address = {rng.randint(0x50, 0x57)}, values = 1)", "record", "int16")
        if part.spi_cs and rng.random() < 0.2:
            self.device("slog", f'SpiEepromLog(cs = "{rng.choice(part.spi_cs)}", values = 1)', "record", "int16")
        if part.encoder_pairs and rng.random() < 0.4:
            a, b = rng.choice(part.encoder_pairs)
            self.device("enc", f'Encoder(pin_a = "{a}", pin_b = "{b}")', "count", "int32", (-100000, 100000))

    # ------------------------------------------------------------ dataflows

    def external_sources(self, task: str) -> list[Signal]:
        out = [Signal(p, t, 1, False) for p, t in self.params.items()]
        out += [Signal(v, t, 1, False) for v, t in self.vars.items() if self.var_writer.get(v) != task]
        out += [Signal(d, t, 1, False) for d, (t, _, _) in self.device_outs.items()]
        return out

    def pick(self, signals: list[Signal], t: str | None, tokens: int | None = None) -> Signal | None:
        """A signal that may feed an input of type ``t`` (equal or widening)."""
        ok = [s for s in signals if (tokens is None or s.tokens == tokens) and
              (t is None or s.type == t or (self.opt.widening and widens(s.type, t)))]
        if not ok:
            return None
        same = [s for s in ok if s.type == t]
        if same and self.rng.random() < 0.6:
            return self.rng.choice(same)
        return self.rng.choice(ok)

    def edge(self, src: Signal, dst: str) -> str:
        """``src -> dst``, with initial tokens now and then between actors."""
        rng = self.rng
        delay = ""
        if src.actor and dst.count(".") == 1 and rng.random() < 0.2:
            if rng.random() < 0.5 or src.type == "float32":
                delay = f" delay {rng.randint(1, 3)}"
            else:
                vals = [model_literal(src.type, boundary(rng, src.type)) for _ in range(rng.randint(1, 3))]
                delay = f" delay [{', '.join(vals)}]"
        return f"    {src.ref} -> {dst}{delay}"

    def dataflow(self, name: str, task: str, *, in_chart: bool) -> str:
        """A dataflow run by ``task`` (in one of its chart's steps when
        ``in_chart``: no channel there)."""
        rng = self.rng
        signals = self.external_sources(task)
        lines: list[str] = []
        insts: list[str] = []
        feedback: list[tuple[str, Port, int]] = []  # (instance, port, tokens)
        channel = None
        self.head_lines = []
        if not in_chart and self.opt.channels and rng.random() < 0.3:
            channel = self.consume_channel(task, signals)
        insts += self.head_lines
        for i in range(rng.randint(1, self.opt.max_actors)):
            inst = f"a{i}"
            use, tokens = self.choose_actor(signals)
            if use is None:
                continue
            insts.append(f"    {inst} = {use.decl}")
            fed_back = False
            for port in use.inputs:
                need = tokens * port.rate
                if (not fed_back and len(use.inputs) > 1 and port is use.inputs[-1] and rng.random() < 0.3):
                    feedback.append((inst, port, need))
                    fed_back = True
                    continue
                src = self.pick(signals, port.type, need)
                if src is not None and src.ref in self.channels:
                    signals.remove(src)  # a channel has one consuming edge
                if src is None:  # a constant of the type, always possible
                    src = self.constant_source(port.type, need, lines, insts)
                lines.append(self.edge(src, f"{inst}.{port.name}"))
            for port in use.outputs:
                signals.append(Signal(f"{inst}.{port.name}", port.type, tokens * port.rate, True, i))
        for inst, port, need in feedback:
            later = [s for s in signals if s.actor and s.tokens == need and
                     (s.type == port.type or (self.opt.widening and widens(s.type, port.type)))]
            src = rng.choice(later) if later else self.constant_source(port.type, need, lines, insts)
            delay = f" delay {need}" if src.actor else ""
            lines.append(f"    {src.ref} -> {inst}.{port.name}{delay}")
        if channel is not None and channel in signals:  # nothing read it
            signals.remove(channel)
            lines.append(f"    {channel.ref} -> {self.new_var(channel.type, task)}")
        self.sinks(task, signals, lines, in_chart)
        body = insts + lines
        sched = rng.choice(["", "", " schedule flat", " schedule min-buffer"])
        if feedback and sched == " schedule flat":
            sched = ""
        return "\n".join([f"dataflow {name}{sched} {{"] + body + ["}"])

    def constant_source(self, t: str, tokens: int, lines: list[str], insts: list[str]) -> Signal:
        """A Const actor (upsampled to ``tokens``) when nothing else fits."""
        k = self.fresh("c")
        value = model_literal(t, boundary(self.rng, t))
        if t == "bool":
            insts.append(f"    {k} = Select<bool>()")
            for port in ("sel", "a", "b"):
                lines.append(f"    {self.first_param_or_true()} -> {k}.{port}")
        else:
            insts.append(f"    {k} = Const<{t}>(value = {value})")
        if tokens == 1:
            return Signal(f"{k}.y", t, 1, True)
        u = self.fresh("up")
        insts.append(f"    {u} = Upsample<{t}>(factor = {tokens})")
        lines.append(f"    {k}.y -> {u}.x")
        return Signal(f"{u}.y", t, tokens, True)

    def first_param_or_true(self) -> str:
        bools = [p for p, t in self.params.items() if t == "bool"]
        if bools:
            return bools[0]
        name = self.fresh("pb")
        self.params[name] = "bool"
        self.decls.append(f"param {name}: bool = true")
        return name

    def choose_actor(self, signals: list[Signal]) -> tuple[ActorUse | None, int]:
        """An actor and its firings' token scale (tokens of a rate-1 port
        per iteration)."""
        rng = self.rng
        roll = rng.random()
        tokens = rng.choice(sorted({s.tokens for s in signals} or {1}))
        if roll < 0.2:
            kind = rng.choice(MULTIRATE)
            typed = [s for s in signals if s.tokens == tokens and s.type in self.catalog.numeric + ["bool"]]
            if not typed:
                return None, 1
            t = rng.choice(typed).type
            if kind == "WindowStats" and t == "bool":
                kind = "Downsample"
            if kind == "Upsample":
                f = rng.choice([f for f in (1, 2, 3) if tokens * f <= MAX_TOKENS] or [1])
                return self.catalog.multirate(kind, t, f), tokens
            divisors = [f for f in range(1, tokens + 1) if tokens % f == 0]
            f = rng.choice(divisors)
            return self.catalog.multirate(kind, t, f), tokens // f
        if roll < 0.45:
            use = self.catalog.user()
            rates = [p.rate for p in use.inputs]
            options = [q for q in range(1, MAX_TOKENS + 1)
                       if all(q * r <= MAX_TOKENS for r in rates + [p.rate for p in use.outputs])]
            preferred = [q for q in options if any(s.tokens == q * rates[0] for s in signals)]
            return use, rng.choice(preferred or options)
        kind = rng.choice(STD_SINGLE_RATE)
        want = None
        if kind not in ("Const", "Ramp", "SquareWave", "Linear", "Counter", "Pt100Linearize"):
            pool = [s.type for s in signals if s.tokens == tokens and s.type in
                    (INT_NAMES if kind in INTEGER_ONLY else self.catalog.numeric)]
            want = rng.choice(pool) if pool and rng.random() < 0.8 else (
                rng.choice(INT_NAMES) if kind in INTEGER_ONLY else self.catalog.number())
        if kind in ("Const", "Ramp", "SquareWave"):
            tokens = 1
        return self.catalog.std(kind, want), tokens

    def sinks(self, task: str, signals: list[Signal], lines: list[str], in_chart: bool) -> None:
        """Outputs to vars (new ones and, now and then, the task's own
        again), device inputs and a channel."""
        rng = self.rng
        outs = [s for s in signals if s.actor]
        single = [s for s in outs if s.tokens == 1]
        rng.shuffle(single)
        for s in single[: rng.randint(1, 4)]:
            t = s.type
            if self.opt.widening and t in INTS and rng.random() < 0.2:
                t = rng.choice([w for w in INT_NAMES if widens(s.type, w)])
            lines.append(f"    {s.ref} -> {self.new_var(t, task)}")
        for datum, t in self.device_ins.items():
            if self.device_in_writer.get(datum, task) != task or rng.random() < 0.5:
                continue
            src = self.pick(single, t)
            if src is not None:
                self.device_in_writer[datum] = task
                lines.append(f"    {src.ref} -> {datum}")
        if not in_chart and self.opt.channels and outs and rng.random() < 0.4:
            src = rng.choice(outs)
            name = self.fresh("ch")
            self.channels.append(name)
            self.pending_channels.append((name, src.type, src.tokens, task))
            lines.append(f"    {src.ref} -> {name}")


    def consume_channel(self, task: str, signals: list[Signal]) -> Signal | None:
        """The consuming end of a channel another task produces, when the
        periods allow a balance of at most MAX_TOKENS per activation."""
        me = self.task_by_name(task)
        for k, (name, t, tokens, producer) in enumerate(self.pending_channels):
            if producer == task:
                continue
            prod = self.task_by_name(producer)
            num = tokens * me.period_ms
            if num % prod.period_ms or not 0 < num // prod.period_ms <= MAX_TOKENS:
                continue
            del self.pending_channels[k]
            self.consumed.append((name, t))
            tokens = num // prod.period_ms
            if tokens == 1:
                signal = Signal(name, t, 1, False)
                signals.append(signal)
                return signal
            # one consuming actor that fires once per activation keeps the
            # graph's repetitions (and so the balance) as computed here
            head = self.fresh("head")
            if t in INTS and self.rng.random() < 0.5:
                self.head_lines = [f"    {head} = WindowStats<{t}>(n = {tokens})", f"    {name} -> {head}.x"]
                signals += [Signal(f"{head}.{p}", t, 1, True) for p in ("min", "max", "mean")]
            else:
                self.head_lines = [f"    {head} = Downsample<{t}>(factor = {tokens})", f"    {name} -> {head}.x"]
                signals.append(Signal(f"{head}.y", t, 1, True))
            return None
        return None


    def task_by_name(self, name: str) -> Task:
        return next(t for t in self.tasks if t.name == name)

    # ------------------------------------------------------------ whole model

    def write(self) -> str:
        rng = self.rng
        self.items()
        self.devices()
        for i in range(rng.randint(1, 3)):
            period = rng.choice([1, 2, 4, 5, 10])
            offset = rng.choice([0, 0, rng.randint(0, period - 1) * 1000, 500 if period > 1 else 0])
            deadline = rng.choice([period * 1000, period * 1000, rng.randint(1, period) * 1000])
            self.tasks.append(Task(f"t{i}", period, offset, deadline))
        flows = []
        for task in self.tasks:
            for _ in range(rng.randint(1, 2)):
                if self.opt.charts and rng.random() < 0.35:
                    name = self.fresh("Chart")
                    flows.append(chart_text(self, name, task))
                else:
                    name = self.fresh("Flow")
                    flows.append(self.dataflow(name, task.name, in_chart=False))
                task.runs.append(name)
        # a produced channel nobody consumed: consume it in a task of its own
        for name, t, tokens, producer in list(self.pending_channels):
            self.pending_channels = [(name, t, tokens, producer)]
            prod = self.task_by_name(producer)
            task = Task(self.fresh("tc"), prod.period_ms, 0, prod.period_ms * 1000)
            self.tasks.append(task)
            flow = self.fresh("Drain")
            self.head_lines = []
            signals: list[Signal] = []
            self.consume_channel(task.name, signals)
            sink = self.new_var(t, task.name)
            body = self.head_lines + [f"    {signals[0].ref} -> {sink}"]
            flows.append("\n".join([f"dataflow {flow} {{"] + body + ["}"]))
            task.runs.append(flow)
        self.pending_channels = []
        text = [f'model rand{self.seed} "random model {self.seed} for {self.part.name}"', "import std", ""]
        text += [ut.text for ut in self.catalog.user_types] + [""]
        text += self.decls + [f"channel {n}: {t}" for n, t in self.consumed] + [""]
        text += flows + [""]
        for task in self.tasks:
            attrs = f" period {task.period_ms} ms"
            if task.offset_us:
                attrs += f" offset {task.offset_us} us"
            if task.deadline_us != task.period_ms * 1000:
                attrs += f" deadline {task.deadline_us} us"
            text.append(f"task {task.name}{attrs} {{ {' '.join('run ' + r for r in task.runs)} }}")
        return "\n".join(text) + "\n"

    def stimulus(self) -> str:
        """Rows at random instants setting params (within their ranges) and
        device data, in the stimulus format (docs/boards.md)."""
        rng = self.rng
        cols: dict[str, tuple[int, int]] = {}
        for p, t in self.params.items():
            lo, hi = self.param_ranges.get(p, (0, 1) if t == "bool" else (INTS[t].lo, INTS[t].hi))
            cols[p] = (lo, hi)
        for d, (_, lo, hi) in self.device_outs.items():
            cols[d] = (lo, hi)
        inputs = [v for v in self.vars if v not in self.var_writer]
        for v in inputs:
            t = self.vars[v]
            cols[v] = (0, 1) if t == "bool" else (INTS[t].lo, INTS[t].hi)
        names = list(cols)
        rows = []
        encoder = {d: 0 for d in self.device_outs if d.endswith(".count")}
        times = sorted({0} | {rng.randint(0, self.opt.duration_ms * 1000 - 1) for _ in range(rng.randint(3, 25))})
        for t_us in times:
            row = []
            for n in names:
                if t_us and rng.random() < 0.5:
                    row.append("")
                elif n in encoder:
                    encoder[n] = max(-100000, min(100000, encoder[n] + rng.randint(-40, 40)))
                    row.append(str(encoder[n]))
                else:
                    lo, hi = cols[n]
                    row.append(str(rng.choice([lo, hi, rng.randint(lo, hi)])))
            rows.append(",".join([str(t_us)] + row))
        return "\n".join([",".join(["time_us"] + names)] + rows) + "\n"


DRY_CHANNEL = re.compile(r"channel '(\w+)' runs dry.*\n(?:.*\n)*?\s*hint: declare it with: delay (\d+)")


def with_channel_delays(text: str) -> str:
    """``text`` with the initial tokens its channels need: the checker
    computes them (docs/language.md §3) and says so in its hint."""
    from easylab.pipeline import check_file

    for _ in range(3):
        report = check_file("random.elab", text=text).report()
        found = DRY_CHANNEL.findall(report)
        if not found:
            return text
        for name, delay in found:
            text = re.sub(rf"^channel {name}: (\w+)(?: delay \d+)?$", rf"channel {name}: \1 delay {delay}", text,
                          flags=re.M)
    return text


def generate(seed: int, part: str = "atmega2560", options: Options | None = None) -> GeneratedModel:
    """The model and stimulus of ``seed`` for ``part`` (its pins, ADC
    channels, PWM outputs); the same arguments give the same text."""
    writer = ModelWriter(seed, PARTS[part], options or Options())
    text = writer.write()
    if writer.consumed:
        text = with_channel_delays(text)
    return GeneratedModel(f"rand{seed}", seed, part, text, writer.stimulus(), writer.opt.duration_ms)
