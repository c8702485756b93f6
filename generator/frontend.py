"""The front end in one call: read, parse, import, check (and analyse)."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .checker import check
from .loader import load
from .model import CheckedModel
from .source import Diagnostics, SourceCache


@dataclass
class FrontEndResult:
    """The checked model (None when there are errors) and every diagnostic."""

    model: CheckedModel | None
    diagnostics: Diagnostics
    sources: SourceCache

    def report(self) -> str:
        """All diagnostics, rendered with source excerpts."""
        return "\n".join(d.render(self.sources) for d in self.diagnostics.sorted())


def check_file(path: str | Path) -> FrontEndResult:
    """Parse and check a model file and its imports.

    Raises OSError (FileNotFoundError, UnicodeDecodeError as ValueError) only
    for the root file itself; every problem inside a model is a diagnostic.
    """
    sources = SourceCache()
    diags = Diagnostics()
    loaded = load(Path(path), sources, diags)
    model = None
    if loaded is not None and not diags.has_errors:
        model = check(loaded.modules, loaded.root, diags)
    elif loaded is not None:
        # Syntax errors in an import: still check names in what did parse? No:
        # a partial namespace gives misleading follow-on errors.
        pass
    return FrontEndResult(model if not diags.has_errors else None, diags, sources)
