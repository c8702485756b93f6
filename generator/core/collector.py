"""When Python's cycle collector runs, for the code that builds large
object graphs in one go (the SDF schedulers, the language server's checks).

The collector is generational: a pass over the youngest objects runs every
few hundred allocations, and the objects that survive enough passes move
to the oldest generation, which is scanned whole when it has grown by a
quarter. Code that allocates a large structure meant to live (a checked
model) makes it survive those passes one by one and then pays for a scan
of everything the process holds; code that allocates many short-lived
objects pays for passes that find nothing.
"""

from __future__ import annotations

import gc
from contextlib import contextmanager
from typing import Iterator


@contextmanager
def cycle_collection_paused() -> Iterator[None]:
    """Run the block with the cycle collector off (reference counting still
    frees every object without a cycle); the collector is on again after
    it if it was before."""
    enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if enabled:
            gc.enable()


def collect_young() -> None:
    """Free the cyclic garbage of the two young generations, scanning
    nothing older: what a structure built under :func:`cycle_collection_paused`
    left behind once it was dropped, if nothing kept it past a later build."""
    gc.collect(1)


def collect_all() -> None:
    """A full collection: afterwards every object still alive is in the
    oldest generation, where the young collections never look."""
    gc.collect()
