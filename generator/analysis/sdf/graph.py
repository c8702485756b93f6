"""The plain SDF graph model: named actors and rate-annotated edges.

This model is independent of the language front end: the front end (or the
SDF3 importer) builds an :class:`SdfGraph`, and every analysis works on it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Iterable

from .errors import GraphError


def _check_count(value: object, what: str, minimum: int) -> None:
    # bool is an int subclass; a rate of True is a front-end bug, not a rate.
    if not isinstance(value, int) or isinstance(value, bool) or value < minimum:
        raise GraphError(f"{what} must be an integer >= {minimum}, not {value!r}")


@dataclass(frozen=True, eq=False)
class SdfEdge:
    """A FIFO channel from ``src`` to ``dst``.

    ``prod`` tokens are produced per firing of ``src``, ``cons`` consumed per
    firing of ``dst``; ``delay`` tokens are on the channel initially.  ``name``
    is an optional label for messages; ``loc`` is an opaque source position the
    library never inspects, only hands back inside errors.  Edges compare by
    identity, so parallel edges with equal rates stay distinct.
    """

    src: str
    dst: str
    prod: int
    cons: int
    delay: int = 0
    name: str | None = None
    loc: Any = field(default=None, repr=False)

    def __post_init__(self) -> None:
        for end in (self.src, self.dst):
            if not isinstance(end, str) or not end:
                raise GraphError(f"actor names must be non-empty strings, not {end!r}")
        _check_count(self.prod, f"production rate of {self.label}", 1)
        _check_count(self.cons, f"consumption rate of {self.label}", 1)
        _check_count(self.delay, f"delay of {self.label}", 0)

    @property
    def label(self) -> str:
        """The name given by the front end, else ``"src -> dst"``."""
        return self.name if self.name else f"{self.src} -> {self.dst}"

    @property
    def is_self_loop(self) -> bool:
        return self.src == self.dst

    def describe(self) -> str:
        """``label (prod:cons, delay d)``, the form every message uses."""
        delay = f", delay {self.delay}" if self.delay else ""
        return f"{self.label} ({self.prod}:{self.cons}{delay})"


class SdfGraph:
    """Ordered actors and edges; several edges per pair and self-loops allowed.

    Actor order matters: it is the order of the repetition vector, and the
    tie-breaker wherever a scheduler has a free choice, so results are
    deterministic.
    """

    def __init__(
        self,
        actors: Iterable[str] = (),
        edges: Iterable[SdfEdge] = (),
        name: str | None = None,
    ) -> None:
        self.name = name
        self._actors: list[str] = []
        self._actor_set: set[str] = set()
        self._edges: list[SdfEdge] = []
        for actor in actors:
            self.add_actor(actor)
        for edge in edges:
            self.add(edge)

    @property
    def actors(self) -> tuple[str, ...]:
        return tuple(self._actors)

    @property
    def edges(self) -> tuple[SdfEdge, ...]:
        return tuple(self._edges)

    def has_actor(self, name: str) -> bool:
        return name in self._actor_set

    def add_actor(self, name: str) -> str:
        """Append an actor; a duplicate name is an error."""
        if not isinstance(name, str) or not name:
            raise GraphError(f"actor names must be non-empty strings, not {name!r}")
        if name in self._actor_set:
            raise GraphError(f"duplicate actor {name!r}")
        self._actors.append(name)
        self._actor_set.add(name)
        return name

    def add(self, edge: SdfEdge) -> SdfEdge:
        """Append an existing edge object; its actors are added when new."""
        if not isinstance(edge, SdfEdge):
            raise GraphError(f"not an SdfEdge: {edge!r}")
        for end in (edge.src, edge.dst):
            if end not in self._actor_set:
                self.add_actor(end)
        self._edges.append(edge)
        return edge

    def add_edge(
        self,
        src: str,
        dst: str,
        prod: int,
        cons: int,
        delay: int = 0,
        *,
        name: str | None = None,
        loc: Any = None,
    ) -> SdfEdge:
        """Create and append an edge; actors not seen yet are appended first."""
        return self.add(SdfEdge(src, dst, prod, cons, delay, name, loc))

    @classmethod
    def from_edges(
        cls,
        edges: Iterable[tuple],
        actors: Iterable[str] = (),
        name: str | None = None,
    ) -> "SdfGraph":
        """Build from ``(src, dst, prod, cons[, delay])`` tuples.

        ``actors`` fixes the order of (some) actors up front; the others follow
        in order of first mention.
        """
        graph = cls(actors, name=name)
        for spec in edges:
            graph.add_edge(*spec)
        return graph

    def __repr__(self) -> str:
        if len(self._edges) > 40:
            title = f" {self.name!r}" if self.name else ""
            return f"<SdfGraph{title}: {len(self._actors)} actors, {len(self._edges)} edges>"
        # Small graphs print as a constructor call, handy in test failures.
        edges = ", ".join(repr(edge) for edge in self._edges)
        name = f", name={self.name!r}" if self.name else ""
        return f"SdfGraph({self._actors!r}, [{edges}]{name})"
