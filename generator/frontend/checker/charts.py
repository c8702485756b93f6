"""The rules of sequential charts: steps, transitions, actions and the
structure of divergences and convergences (docs/language.md)."""

from __future__ import annotations

from ...core.source import Span, did_you_mean, note
from ...core import types as T
from .. import ast
from ..expressions import Symbol
from ..model import ActionInfo, ChartInfo, StepInfo, TransitionInfo, Writer
from .base import with_article, kind_name


class ChartRules:
    # ================================================================ charts

    def check_chart(self, decl: ast.Chart) -> None:
        steps: dict[str, StepInfo] = {}
        for s in decl.steps:
            if s.name in steps:
                self.error(s.name_span, f"step '{s.name}' is declared twice in chart '{decl.name}'",
                           notes=[note(steps[s.name].decl.name_span, "first declared here")])
                continue
            runs = []
            for r in s.runs:
                df = self.lookup(r.name, r.name_span, (ast.Dataflow,), "dataflow")
                if df is not None and df.name in self.dataflows:
                    runs.append(self.dataflows[df.name])
            steps[s.name] = StepInfo(s, len(steps), (), runs)
        info = ChartInfo(decl, steps, [], None)
        self.charts[decl.name] = info
        initials = [s for s in steps.values() if s.decl.initial]
        if not initials:
            self.error(decl.name_span, f"chart '{decl.name}' has no initial step",
                       "mark the step it starts in: initial step Name { ... }")
        for extra in initials[1:]:
            self.error(extra.decl.span, f"chart '{decl.name}' has more than one initial step",
                       notes=[note(initials[0].decl.span, "the first initial step")])
        info.initial = initials[0] if initials else None
        for idx, t in enumerate(decl.transitions):
            srcs = [self._step_ref(steps, r, decl) for r in t.sources]
            dsts = [self._step_ref(steps, r, decl) for r in t.targets]
            if None in srcs or None in dsts:
                continue
            for group in (t.sources, t.targets):
                names = [r.name for r in group]
                for r in group:
                    if names.count(r.name) > 1:
                        self.error(r.span, f"step '{r.name}' appears twice in one transition")
                        break
            info.transitions.append(TransitionInfo(t, idx, srcs, dsts))
        for s in steps.values():
            for action in s.decl.entry:
                s.entry_actions.extend(self.check_assignment(action, info))
            for action in s.decl.exit:
                s.exit_actions.extend(self.check_assignment(action, info))
        for tr in info.transitions:
            v = self.typer(lambda p: self.chart_symbol(p, info)).check(tr.decl.guard)
            tr.guard = v.node
            if v.type is not None and v.type is not T.BOOL:
                self.error(tr.decl.guard.span, f"a transition guard must be a bool, not '{v.type}'",
                           "compare it, e.g. x > 0")
        if info.initial is not None:
            self.check_chart_structure(info)

    def _step_ref(self, steps, ref: ast.StepRef, decl: ast.Chart):
        s = steps.get(ref.name)
        if s is None:
            self.error(ref.span, f"chart '{decl.name}' has no step '{ref.name}'", did_you_mean(ref.name, steps))
        return s

    def chart_symbol(self, path: ast.Path, chart: ChartInfo):
        if path.parts[0] in chart.steps and path.parts[0] not in self.globals:
            if len(path.parts) != 2 or path.parts[1] not in ("time", "active"):
                return (f"a step offers '{path.parts[0]}.time' and '{path.parts[0]}.active'", None)
            kind = "step_" + path.parts[1]
            return Symbol(kind, T.TIME if path.parts[1] == "time" else T.BOOL, None, chart.steps[path.parts[0]],
                          path.text)
        symbol = self.global_symbol(path)
        if isinstance(symbol, tuple) and path.parts[0] not in self.globals and len(path.parts) > 1:
            # `Idel.time`: a misspelt step rather than a misspelt global
            return symbol[0], did_you_mean(path.parts[0], chart.steps) or symbol[1]
        return symbol

    def check_assignment(self, action: ast.Assign, chart: ChartInfo) -> list[ActionInfo]:
        target = action.target
        head = self.globals.get(target.parts[0])
        if isinstance(head, ast.Data) and len(target.parts) == 1:
            if head.kind == "param":
                self.error(target.span, f"param '{head.name}' cannot be assigned by a chart",
                           "params are written only through the debug and service interfaces; use a var")
                return []
            data = self.data.get(head.name)
            if data is None:
                return []
            t, writers = data.type, data.writers
        elif isinstance(head, ast.DeviceInstance):
            datum = self.device_datum(target)
            if isinstance(datum, tuple):
                self.error(target.span, *datum)
                return []
            if datum.port.direction != "in":
                self.error(target.span, f"'{target.text}' is a device output; only device inputs can be assigned")
                return []
            t, writers = datum.type, datum.writers
        else:
            what = with_article(kind_name(head)) if head is not None else "not declared"
            hint = None if head is not None else did_you_mean(target.parts[0], [
                n for n, d in self.globals.items() if isinstance(d, ast.Data) and d.kind == "var"])
            self.error(target.span, f"cannot assign to '{target.text}': it is {what}; "
                                    "an action assigns a var or a device input", hint)
            return []
        v = self.typer(lambda p: self.chart_symbol(p, chart)).expect(action.value, t,
                                                                    f"the value assigned to '{target.text}'")
        writers.append(Writer(chart, action.span))
        if v.type is None:
            return []
        return [ActionInfo(action, datum if isinstance(head, ast.DeviceInstance) else data, v.node)]

    def check_chart_structure(self, chart: ChartInfo) -> None:
        """Reachability and parallel branches (docs/language.md, 'charts').

        Every step gets the branch it runs in: the initial step the root
        branch (); a divergence ``S -> (A, B)`` puts A and B in branches
        (t, 0) and (t, 1) below S's; a convergence must join exactly the
        branches of one divergence and leads back to the branch above them.
        """
        branch: dict[str, tuple] = {chart.initial.name: ()}
        where: dict[str, Span] = {chart.initial.name: chart.initial.decl.name_span}
        divergences: dict[int, int] = {}
        changed = True
        reported: set[int] = set()
        rounds = 0
        while changed and rounds <= len(chart.transitions) + 1:
            changed = False
            rounds += 1
            for tr in chart.transitions:
                if tr.index in reported or any(s.name not in branch for s in tr.sources):
                    continue
                src_branches = [branch[s.name] for s in tr.sources]
                if len(tr.sources) == 1:
                    base = src_branches[0]
                else:
                    base = self._convergence_base(tr, src_branches, divergences)
                    if base is None:
                        reported.add(tr.index)
                        continue
                if len(tr.targets) == 1:
                    targets = {tr.targets[0].name: base}
                else:
                    divergences[tr.index] = len(tr.targets)
                    targets = {t.name: base + ((tr.index, i),) for i, t in enumerate(tr.targets)}
                for name, b in targets.items():
                    if name not in branch:
                        branch[name] = b
                        where[name] = tr.decl.span
                        changed = True
                    elif branch[name] != b:
                        reported.add(tr.index)
                        self.error(tr.decl.span, f"step '{name}' is entered from two different parallel branches",
                                   "a step belongs to one branch; join branches with a convergence (A, B) -> C",
                                   [note(where[name], f"'{name}' is entered here too")])
        for s in chart.steps.values():
            if s.name not in branch:
                self.error(s.decl.name_span, f"step '{s.name}' is unreachable from the initial step "
                                             f"'{chart.initial.name}'")
            else:
                s.branch = branch[s.name]

    def _convergence_base(self, tr: TransitionInfo, src_branches, divergences):
        tails = {b[-1] if b else None for b in src_branches}
        bases = {b[:-1] for b in src_branches}
        divs = {t[0] for t in tails if t is not None}
        ok = None not in tails and len(bases) == 1 and len(divs) == 1
        if ok:
            div = divs.pop()
            indices = sorted(t[1] for t in tails)
            ok = indices == list(range(divergences.get(div, -1)))
        if not ok:
            self.error(tr.decl.span, "a convergence must join one step of every branch of a single divergence",
                       "join exactly the branches that one 'A -> (B, C)' transition started")
            return None
        return bases.pop()

