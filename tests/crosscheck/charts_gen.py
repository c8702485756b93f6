"""Random charts (IEC 61131-3 style SFC) and the model-language
expressions of their guards and actions: a cycle of steps, now and then a
divergence into parallel branches that a convergence joins again, timed
guards (`Step.time`), `Step.active`, entry and exit actions on the task's
vars and device inputs, and dataflows run by the steps."""

from __future__ import annotations

from ctypes_gen import INTS, boundary, model_literal


class Expressions:
    """Expressions of the model language over a model's items. Binary
    operators keep a non-constant left operand, so no constant
    sub-expression can overflow at compile time."""

    def __init__(self, writer, steps: list[str]) -> None:
        self.w = writer
        self.rng = writer.rng
        self.steps = steps

    def names(self, t: str) -> list[str]:
        w = self.w
        found = [n for n, vt in list(w.params.items()) + list(w.vars.items()) if vt == t]
        found += [d for d, (dt, _, _) in w.device_outs.items() if dt == t]
        return found

    def value(self, t: str, depth: int = 2) -> str:
        """An expression of integer type ``t`` (never constant when a name
        of the type exists)."""
        rng = self.rng
        names = self.names(t)
        if not names:
            return model_literal(t, boundary(rng, t))
        expr = rng.choice(names)
        for _ in range(rng.randint(0, depth)):
            op = rng.choice(["+", "-", "*", "/", "%"])
            if op in "/%":
                right = rng.choice(names + [str(rng.choice([1, 2, 3, 7, 10, 100]))])
            else:
                consts = [k for k, kt in self.w.consts.items() if kt == t]
                right = rng.choice(names + consts + [model_literal(t, boundary(rng, t))])
            expr = f"({expr} {op} {right})"
        return expr

    def guard(self, depth: int = 2) -> str:
        rng = self.rng
        roll = rng.random()
        if depth > 0 and roll < 0.2:
            return f"({self.guard(depth - 1)} {rng.choice(['and', 'or'])} {self.guard(depth - 1)})"
        if depth > 0 and roll < 0.3:
            return f"not {self.guard(depth - 1)}"
        if roll < 0.5 and self.steps:
            step = rng.choice(self.steps)
            if rng.random() < 0.7:
                return f"{step}.time {rng.choice(['>', '>=', '<'])} {rng.choice([0, 1, 2, 3, 5, 10, 20])} ms"
            return f"{step}.active"
        bools = self.names("bool")
        if bools and roll < 0.7:
            return rng.choice(bools)
        t = rng.choice([t for t in INTS if self.names(t)] or ["int16"])
        return f"{self.value(t, 1)} {rng.choice(['<', '<=', '>', '>=', '==', '!='])} " \
               f"{model_literal(t, boundary(rng, t))}"


def chart_text(writer, name: str, task) -> str:
    """A chart run by ``task`` and the dataflows its steps run, as text."""
    rng = writer.rng
    n = rng.randint(2, 4)
    main = [f"{name}_S{i}" for i in range(n)]
    steps = list(main)
    transitions = []
    branches = None
    if rng.random() < 0.5:
        left = [f"{name}_L{i}" for i in range(rng.randint(1, 2))]
        right = [f"{name}_R{i}" for i in range(rng.randint(1, 2))]
        steps += left + right
        branches = (left, right)
    ex = Expressions(writer, steps)
    if branches:
        left, right = branches
        transitions.append(f"transition {main[0]} -> ({left[0]}, {right[0]}) when {ex.guard()}")
        for seq in (left, right):
            for a, b in zip(seq, seq[1:]):
                transitions.append(f"transition {a} -> {b} when {ex.guard()}")
        transitions.append(f"transition ({left[-1]}, {right[-1]}) -> {main[1]} when {ex.guard()}")
        rest = main[1:]
    else:
        rest = main
    for a, b in zip(rest, rest[1:]):
        transitions.append(f"transition {a} -> {b} when {ex.guard()}")
    transitions.append(f"transition {main[-1]} -> {main[0]} when {ex.guard()}")
    if rng.random() < 0.5:  # a second way out of a step, declared later: the first wins on a tie
        a = rng.choice(main)
        b = rng.choice([s for s in main if s != a] or main)
        if a != b:
            transitions.append(f"transition {a} -> {b} when {ex.guard()}")
    # the chart's own vars: written by its actions only
    targets = {writer.new_var(rng.choice(list(INTS) + ["bool"]), task.name): None for _ in range(rng.randint(1, 3))}
    targets = {v: writer.vars[v] for v in targets}
    for datum, t in writer.device_ins.items():
        if datum not in writer.device_in_writer and rng.random() < 0.3:
            writer.device_in_writer[datum] = task.name
            targets[datum] = t
    flows = []
    runnable = []
    for _ in range(rng.randint(0, 2)):
        flow = writer.fresh("Step")
        flows.append(writer.dataflow(flow, task.name, in_chart=True))
        runnable.append(flow)
    body = []
    runs = {s: [] for s in steps}
    for flow in runnable:  # every dataflow of the chart runs in a step or more
        for s in rng.sample(steps, rng.randint(1, min(2, len(steps)))):
            runs[s].append(f"run {flow}")
    for i, s in enumerate(steps):
        actions = []
        for _ in range(rng.randint(0, 2)):
            target = rng.choice(list(targets))
            t = targets[target]
            value = ex.guard(1) if t == "bool" else ex.value(t)
            actions.append(f"{rng.choice(['entry', 'exit'])} {target} = {value}")
        actions += runs[s]
        head = "initial step" if i == 0 else "step"
        body.append(f"    {head} {s} {{ {'  '.join(actions)} }}")
    chart = [f"chart {name} {{"] + body + [f"    {t}" for t in transitions] + ["}"]
    return "\n".join(flows + ["\n".join(chart)])
