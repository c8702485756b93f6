"""A DFA lexer from regular expressions, for tools/tree_sitter_grammar.py:
each terminal's expression (Python's own regex parser) as a Thompson NFA,
the NFAs of a set of terminals as one DFA over code point ranges, longest
match first, then the terminal that ranks first; a terminal with a
non-greedy repeat stops at its first match (``/* ... */``)."""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

MAX_CHAR = 0x10FFFF


class Nfa:
    """A Thompson NFA over code point ranges."""

    def __init__(self):
        self.eps: list[list[int]] = []
        self.edges: list[list[tuple[tuple[tuple[int, int], ...], int]]] = []
        self.owner: list[str | None] = []

    def state(self, owner: str) -> int:
        self.eps.append([])
        self.edges.append([])
        self.owner.append(owner)
        return len(self.eps) - 1


def _ranges_of_set(items, negate: bool) -> list[tuple[int, int]]:
    from re import _constants as c

    ranges = []
    for op, arg in items:
        if op is c.LITERAL:
            ranges.append((arg, arg))
        elif op is c.RANGE:
            ranges.append(arg)
        elif op is c.CATEGORY and arg is c.CATEGORY_DIGIT:
            ranges.append((48, 57))
        else:
            raise ValueError(f"unsupported character set item {op} {arg}")
    ranges = normalise(ranges)
    return _complement(ranges) if negate else ranges


def normalise(ranges) -> list[tuple[int, int]]:
    out: list[list[int]] = []
    for lo, hi in sorted(ranges):
        if out and lo <= out[-1][1] + 1:
            out[-1][1] = max(out[-1][1], hi)
        else:
            out.append([lo, hi])
    return [(lo, hi) for lo, hi in out]


def _complement(ranges) -> list[tuple[int, int]]:
    # Code point 0 is the lexer's end of input: no token goes on over it.
    out, low = [], 1
    for lo, hi in ranges:
        if lo > low:
            out.append((low, lo - 1))
        low = max(low, hi + 1)
    if low <= MAX_CHAR:
        out.append((low, MAX_CHAR))
    return out


def add_regex(nfa: Nfa, owner: str, pattern: str, flags: int = 0) -> tuple[int, int, bool]:
    """The NFA of ``pattern``: (start, accept, lazy). ``lazy`` says the
    pattern has a non-greedy repeat: it then matches the shortest text."""
    from re import _constants as c
    from re import _parser

    lazy = False

    def piece(items) -> tuple[int, int]:
        start = nfa.state(owner)
        end = start
        for op, arg in items:
            s, e = node(op, arg)
            nfa.eps[end].append(s)
            end = e
        return start, end

    def chars(ranges) -> tuple[int, int]:
        s, e = nfa.state(owner), nfa.state(owner)
        nfa.edges[s].append((tuple(ranges), e))
        return s, e

    def node(op, arg) -> tuple[int, int]:
        nonlocal lazy
        if op is c.LITERAL:
            return chars([(arg, arg)])
        if op is c.NOT_LITERAL:
            return chars(_complement([(arg, arg)]))
        if op is c.ANY:
            return chars(_complement([(10, 10)]))
        if op is c.IN:
            negate = bool(arg) and arg[0][0] is c.NEGATE
            return chars(_ranges_of_set(arg[1:] if negate else arg, negate))
        if op is c.SUBPATTERN:
            return piece(arg[3])
        if op is c.BRANCH:
            s, e = nfa.state(owner), nfa.state(owner)
            for alternative in arg[1]:
                a, b = piece(alternative)
                nfa.eps[s].append(a)
                nfa.eps[b].append(e)
            return s, e
        if op in (c.MAX_REPEAT, c.MIN_REPEAT):
            lazy = lazy or op is c.MIN_REPEAT
            low, high, sub = arg
            s = nfa.state(owner)
            end = s
            for _ in range(low):
                a, b = piece(sub)
                nfa.eps[end].append(a)
                end = b
            if high is c.MAXREPEAT:
                a, b = piece(sub)
                loop = nfa.state(owner)
                nfa.eps[end].append(loop)
                nfa.eps[loop].append(a)
                nfa.eps[b].append(loop)
                end = loop
            else:
                tail = nfa.state(owner)
                for _ in range(high - low):
                    a, b = piece(sub)
                    nfa.eps[end].append(a)
                    nfa.eps[end].append(tail)
                    end = b
                nfa.eps[end].append(tail)
                end = tail
            return s, end
        raise ValueError(f"unsupported regular expression part {op} in {pattern!r}")

    start, accept = piece(_parser.parse(pattern, flags))
    return start, accept, lazy


@dataclass
class LexState:
    accept: str | None = None                      # terminal key accepted here
    moves: list[tuple[list[tuple[int, int]], int, bool]] = field(default_factory=list)  # ranges, target, skip
    eof_to: int | None = None


class LexerBuilder:
    """DFA states for several start sets over one NFA, shared where equal."""

    def __init__(self, patterns: dict[str, tuple[str, int]], rank: dict[str, tuple]):
        self.nfa = Nfa()
        self.start: dict[str, int] = {}
        self.accept: dict[int, str] = {}
        self.lazy: set[str] = set()
        self.rank = rank
        for key, (pattern, flags) in patterns.items():
            s, a, lazy = add_regex(self.nfa, key, pattern, flags)
            self.start[key], self.accept[a] = s, key
            if lazy:
                self.lazy.add(key)
        self.states: list[LexState] = []
        self.ids: dict[tuple, int] = {}
        self.pending: deque = deque()

    def _closure(self, states) -> frozenset:
        stack = list(states)
        seen = set(stack)
        while stack:
            for t in self.nfa.eps[stack.pop()]:
                if t not in seen:
                    seen.add(t)
                    stack.append(t)
        done = {self.accept[s] for s in seen if s in self.accept and self.accept[s] in self.lazy}
        if done:  # a non-greedy terminal stops at its first match
            seen = {s for s in seen if self.nfa.owner[s] not in done or s in self.accept}
        return frozenset(seen)

    def _state(self, key: tuple, nfa_states: frozenset) -> int:
        if key not in self.ids:
            self.ids[key] = len(self.states)
            self.states.append(LexState())
            self.pending.append((self.ids[key], nfa_states))
        return self.ids[key]

    def add_mode(self, terminals, skip: list[tuple[int, int]], eof_state: int | None) -> int:
        """The start state of a lexer for ``terminals`` that skips ``skip``
        characters before a token and accepts the end of input where
        ``eof_state`` is given."""
        nfa_states = self._closure(self.start[t] for t in sorted(terminals))
        first = self._state(("start", nfa_states, tuple(skip), eof_state), nfa_states)
        self._run()
        state = self.states[first]
        if skip and not any(target == first and is_skip for _, target, is_skip in state.moves):
            state.moves.append((skip, first, True))
        state.eof_to = eof_state
        return first

    def add_accepting(self, terminal: str) -> int:
        """A state that only accepts ``terminal`` (the end of input)."""
        index = self._state(("accept", terminal), frozenset())
        self._run()
        self.states[index].accept = terminal
        return index

    def _run(self):
        while self.pending:
            index, nfa_states = self.pending.popleft()
            accepted = [self.accept[s] for s in nfa_states if s in self.accept]
            state = self.states[index]
            if accepted:
                state.accept = min(accepted, key=self.rank.__getitem__)
            bounds = set()
            for s in nfa_states:
                for ranges, _ in self.nfa.edges[s]:
                    for lo, hi in ranges:
                        bounds.add(lo)
                        bounds.add(hi + 1)
            cuts = sorted(bounds)
            targets: dict[frozenset, list[tuple[int, int]]] = {}
            for lo, nxt in zip(cuts, cuts[1:]):
                moved = {t for s in nfa_states for ranges, t in self.nfa.edges[s]
                         if any(a <= lo <= b for a, b in ranges)}
                if moved:
                    targets.setdefault(self._closure(moved), []).append((lo, nxt - 1))
            for nfa_target, ranges in targets.items():
                target = self._state(("set", nfa_target), nfa_target)
                state.moves.append((normalise(ranges), target, False))
            state.moves.sort(key=lambda m: m[0][0])
