"""Size limits that keep the super-linear algorithms bounded."""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class SdfOptions:
    """Tuning knobs of the schedulers; the defaults suit graphs up to 10,000 actors.

    * ``apgan_max_nodes``: APGAN (quadratic to cubic) runs on acyclic levels of
      at most this many nodes; larger ones use RPMC and the topological order.
    * ``dppo_window``: DPPO (cubic) optimises whole levels of at most this many
      nodes; on larger ones, every maximal range of the heuristic's nesting
      with at most this many nodes.
    * ``exact_max_firings`` / ``exact_max_evaluations``: the exact minimum-buffer
      search runs when one iteration has at most that many firings, and tries
      at most that many capacity vectors.
    """

    apgan_max_nodes: int = 128
    dppo_window: int = 64
    exact_max_firings: int = 5_000
    exact_max_evaluations: int = 300
