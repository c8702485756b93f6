"""Size limits that keep the super-linear algorithms bounded."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SdfOptions:
    """Tuning knobs of the schedulers; the defaults suit graphs up to 10,000 actors.

    * ``apgan_search_limit``: APGAN checks that a merge keeps the graph acyclic
      by a search it abandons after this many nodes (then skipping the merge),
      so it is exact on graphs up to that size and near-linear beyond.
    * ``dppo_max_nodes``: DPPO (cubic) optimises whole levels of at most this
      many nodes exactly.
    * ``dppo_window``: on larger levels, DPPO optimises every maximal range of
      the heuristic's nesting with at most this many nodes.
    * ``exact_max_firings`` / ``exact_max_evaluations``: the exact minimum-buffer
      search runs when one iteration has at most that many firings, and tries
      at most that many capacity vectors.
    * ``max_flat_firings``: a flat (minimum-buffer) schedule is refused for
      iterations of more firings than this; its run-length form would be of
      that order, too long to generate code from.
    """

    apgan_search_limit: int = 1_000
    dppo_max_nodes: int = 64
    dppo_window: int = 32
    exact_max_firings: int = 5_000
    exact_max_evaluations: int = 300
    max_flat_firings: int = 5_000_000
