"""Looped schedules: a tree of loops over actor firings, and its notations.

A schedule is a sequence of nodes; a node is either ``Fire(actor, count)``
(``count`` firings of one actor back to back) or ``Loop(count, body)`` (the
body sequence repeated ``count`` times).  Code generation walks the tree;
``firings()`` and ``runs()`` give the flat and run-length forms.

Looped notation (as in Bhattacharyya, Murthy & Lee): a loop is written
``(n body)``, a repeated firing ``(nA)``, a single firing ``A``.  When every
actor name is a single letter the items are written side by side, e.g.
``(7(7(3AB)(2C))(4D))(32E(5F))``; otherwise items are separated by single
spaces, e.g. ``(7 (3 src b) (2 c))``.  A loop count is always followed by a
name or ``(``, so both forms read back unambiguously.

Every traversal here is iterative: trees may be deep and wide.  The
schedulers never build loops of one iteration, so in their schedules the
nesting depth is at most log2 of the largest repetition count, plus one;
recursive code over those trees is safe for realistic graphs.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Iterator, Union


@dataclass(frozen=True)
class Fire:
    """``count`` consecutive firings of ``actor``."""

    actor: str
    count: int = 1

    def __post_init__(self) -> None:
        if not isinstance(self.count, int) or self.count < 1:
            raise ValueError(f"firing count must be a positive integer, not {self.count!r}")


@dataclass(frozen=True)
class Loop:
    """``body`` (a sequence of nodes) executed ``count`` times."""

    count: int
    body: tuple["Node", ...]

    def __post_init__(self) -> None:
        if not isinstance(self.count, int) or self.count < 1:
            raise ValueError(f"loop count must be a positive integer, not {self.count!r}")
        if not isinstance(self.body, tuple):
            object.__setattr__(self, "body", tuple(self.body))
        if not self.body:
            raise ValueError("a loop needs a non-empty body")


Node = Union[Fire, Loop]


def repeat(count: int, items: Iterable[Node]) -> list[Node]:
    """``items`` repeated ``count`` times, as few nested nodes as possible.

    A count of 1 adds no loop, a loop over one firing becomes a repeated
    firing, and a loop over a single loop merges the counts.
    """
    items = list(items)
    if count == 1:
        return items
    if len(items) == 1:
        (only,) = items
        if isinstance(only, Fire):
            return [Fire(only.actor, only.count * count)]
        return [Loop(only.count * count, only.body)]
    return [Loop(count, tuple(items))]


@dataclass(frozen=True)
class Schedule:
    """A looped schedule: the top-level sequence of nodes of one iteration."""

    body: tuple[Node, ...]

    def __post_init__(self) -> None:
        if not isinstance(self.body, tuple):
            object.__setattr__(self, "body", tuple(self.body))

    @classmethod
    def from_runs(cls, runs: Iterable[tuple[str, int]]) -> "Schedule":
        """A flat schedule from ``(actor, count)`` runs, adjacent runs merged."""
        merged: list[list] = []
        for actor, count in runs:
            if merged and merged[-1][0] == actor:
                merged[-1][1] += count
            else:
                merged.append([actor, count])
        return cls(tuple(Fire(actor, count) for actor, count in merged))

    def _walk(self) -> Iterator[Fire]:
        """Every firing node in execution order, loops unrolled."""
        # Frames: [items, next index, iterations still to start].
        stack = [[self.body, 0, 1]]
        while stack:
            frame = stack[-1]
            items, index, _ = frame
            if index == len(items):
                frame[2] -= 1
                if frame[2] == 0:
                    stack.pop()
                else:
                    frame[1] = 0
                continue
            frame[1] = index + 1
            node = items[index]
            if isinstance(node, Fire):
                yield node
            else:
                stack.append([node.body, 0, node.count])

    def runs(self) -> Iterator[tuple[str, int]]:
        """The firing sequence in run-length form, adjacent runs merged."""
        actor, count = None, 0
        for node in self._walk():
            if node.actor == actor:
                count += node.count
            else:
                if actor is not None:
                    yield actor, count
                actor, count = node.actor, node.count
        if actor is not None:
            yield actor, count

    def run_length(self) -> list[tuple[str, int]]:
        """``list(runs())``."""
        return list(self.runs())

    def firings(self) -> Iterator[str]:
        """The flat firing sequence, one actor name per firing."""
        for node in self._walk():
            for _ in range(node.count):
                yield node.actor

    def _nodes(self) -> Iterator[tuple[Node, int]]:
        """Every node once (loops not unrolled), with its total multiplier."""
        stack = [(node, 1) for node in reversed(self.body)]
        while stack:
            node, multiplier = stack.pop()
            yield node, multiplier
            if isinstance(node, Loop):
                inner = multiplier * node.count
                stack.extend((child, inner) for child in reversed(node.body))

    def fire_nodes(self) -> Iterator[Fire]:
        """Every ``Fire`` node once, in text order (loops not unrolled)."""
        for node, _ in self._nodes():
            if isinstance(node, Fire):
                yield node

    def firing_counts(self) -> dict[str, int]:
        """How often each actor fires in the whole schedule."""
        counts: dict[str, int] = {}
        for node, multiplier in self._nodes():
            if isinstance(node, Fire):
                counts[node.actor] = counts.get(node.actor, 0) + node.count * multiplier
        return counts

    def appearances(self) -> dict[str, int]:
        """How often each actor's name appears in the schedule text."""
        counts: dict[str, int] = {}
        for node in self.fire_nodes():
            counts[node.actor] = counts.get(node.actor, 0) + 1
        return counts

    @property
    def is_single_appearance(self) -> bool:
        return all(count == 1 for count in self.appearances().values())

    def text(self, compact: bool | None = None) -> str:
        """Looped notation; ``compact`` defaults to "all names one letter"."""
        if compact is None:
            compact = all(len(name) == 1 and name.isalpha() for name in self.appearances())
        separator = "" if compact else " "
        parts: list[str] = []
        # Entries are nodes to print (with "needs a separator first") or
        # literal closing parentheses.
        stack: list = [(node, i > 0) for i, node in reversed(list(enumerate(self.body)))]
        while stack:
            entry = stack.pop()
            if isinstance(entry, str):
                parts.append(entry)
                continue
            node, separated = entry
            if separated:
                parts.append(separator)
            if isinstance(node, Fire):
                parts.append(
                    node.actor if node.count == 1 else f"({node.count}{separator}{node.actor})"
                )
            else:
                parts.append(f"({node.count}")
                stack.append(")")
                stack.extend((child, True) for child in reversed(node.body))
        return "".join(parts)

    def __str__(self) -> str:
        return self.text()
