"""Exceptions raised by the SDF library.

Every exception that points at parts of the graph carries the offending edges
(`SdfEdge` objects, whose ``loc`` the front end set) so a caller can report
source positions; the message itself is complete and readable on its own.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

if TYPE_CHECKING:  # pragma: no cover - imports for type checkers only
    from .graph import SdfEdge


class SdfError(Exception):
    """Base class of all errors of the SDF library."""

    def __init__(self, message: str, edges: Sequence["SdfEdge"] = ()) -> None:
        super().__init__(message)
        self.message = message
        self.edges: list[SdfEdge] = list(edges)


class GraphError(SdfError, ValueError):
    """The graph itself is malformed (bad rate, unknown actor, duplicate name)."""


class InconsistentGraphError(SdfError):
    """The balance equations have no positive solution.

    ``edges`` is an undirected cycle (each edge shares an actor with the next,
    the last with the first) whose rates contradict each other: going round it,
    the products of production over consumption rates do not multiply to 1.
    """


class DeadlockError(SdfError):
    """The graph cannot complete one iteration from its initial tokens.

    ``edges`` is a directed cycle of blocked actors that lacks tokens;
    ``missing_edge`` is the edge of that cycle whose delay should grow and
    ``missing`` the number of extra initial tokens it needs for the cycle to
    complete its iteration (other, separate cycles may need their own).
    """

    def __init__(
        self,
        message: str,
        edges: Sequence["SdfEdge"],
        missing_edge: "SdfEdge",
        missing: int,
    ) -> None:
        super().__init__(message, edges)
        self.missing_edge = missing_edge
        self.missing = missing


class ScheduleError(SdfError):
    """A schedule is not admissible and periodic for its graph, or none exists."""


class Sdf3Error(SdfError):
    """An SDF3 XML document could not be read (malformed or unsupported)."""
