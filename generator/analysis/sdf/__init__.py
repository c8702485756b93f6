"""Synchronous dataflow (SDF) analysis and scheduling, as a pure library.

Build an :class:`SdfGraph` (or load one with :func:`load_sdf3`), then call
:func:`analyze`.  See docs/sdf.md for the semantics and algorithms.
"""

from .analysis import SCHEDULE_KINDS, Analysis, analyze
from .buffers import (
    edge_lower_bound,
    min_edge_bound,
    sas_edge_bound,
    sas_lower_bound,
    verify,
)
from .cache import AnalysisCache
from .errors import (
    DeadlockError,
    GraphError,
    InconsistentGraphError,
    ScheduleError,
    Sdf3Error,
    SdfError,
)
from .execution import check_deadlock
from .graph import SdfEdge, SdfGraph
from .options import SdfOptions
from .repetitions import repetition_vector
from .schedule import Fire, Loop, Node, Schedule, repeat
from .sdf3 import MAX_SDF3_BYTES, XmlLocation, load_sdf3

__all__ = [
    "SCHEDULE_KINDS", "Analysis", "AnalysisCache", "analyze",
    "edge_lower_bound", "min_edge_bound", "sas_edge_bound", "sas_lower_bound", "verify",
    "DeadlockError", "GraphError", "InconsistentGraphError", "ScheduleError", "Sdf3Error", "SdfError",
    "check_deadlock", "SdfEdge", "SdfGraph", "SdfOptions", "repetition_vector",
    "Fire", "Loop", "Node", "Schedule", "repeat", "MAX_SDF3_BYTES", "XmlLocation", "load_sdf3",
]
