"""The front end in one call: read, parse, import, check (and analyse)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .analysis import analyze_model
from .checker import check
from .timing import compute_timing
from .loader import load
from .model import CheckedModel
from .source import Diagnostics, SourceCache


@dataclass
class FrontEndResult:
    """The checked model (None when there are errors) and every diagnostic."""

    model: CheckedModel | None
    diagnostics: Diagnostics
    sources: SourceCache
    timing: object = None  # easylab.timing.Timing when the model is good

    def report(self) -> str:
        """All diagnostics, rendered with source excerpts."""
        return "\n".join(d.render(self.sources) for d in self.diagnostics.sorted())


def check_file(path: str | Path, schedule: str | None = None, text: str | None = None) -> FrontEndResult:
    """Parse, check and analyse a model file and its imports.

    ``schedule`` overrides every dataflow's schedule kind (``sas`` or
    ``min-buffer``). ``text``, if given, is read instead of the root file
    (its imports are still files, relative to ``path``).

    Raises OSError (FileNotFoundError, UnicodeDecodeError as ValueError) only
    for the root file itself; every problem inside a model is a diagnostic.
    """
    sources = SourceCache({Path(path): text} if text is not None else None)
    diags = Diagnostics()
    loaded = load(Path(path), sources, diags)
    model = None
    # After a syntax error anywhere the namespace is partial: checking it
    # would only add misleading follow-on errors.
    if loaded is not None and not diags.has_errors:
        model = check(loaded.modules, loaded.root, diags)
    timing = None
    if model is not None:
        analyze_model(model, diags, schedule)
        if not diags.has_errors:
            timing = compute_timing(model, diags)
    ok = not diags.has_errors
    return FrontEndResult(model if ok else None, diags, sources, timing if ok else None)


def lower_file(path: str | Path, schedule: str | None = None, text: str | None = None):
    """Front end, analyses and lowering: (IR program or None, FrontEndResult)."""
    from .ir import lower

    result = check_file(path, schedule, text)
    if result.model is None:
        return None, result
    return lower(result.model, result.timing), result
