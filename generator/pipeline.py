"""The pipeline up to the IR in one call: read, parse, import, check,
analyse (SDF, task timing) and lower."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from .analysis.dataflow import analyze_model
from .analysis.timing import compute_timing
from .core.source import Diagnostics, SourceCache
from .frontend.checker import check
from .frontend.loader import library_path, load
from .frontend.model import CheckedModel
from .ir.lower import lower
from .ir.program import Program


@dataclass
class FrontEndResult:
    """The checked model (None when there are errors) and every diagnostic."""

    model: CheckedModel | None
    diagnostics: Diagnostics
    sources: SourceCache
    timing: object = None  # the analysis.timing.Timing when the model is good

    def report(self) -> str:
        """All diagnostics, rendered with source excerpts."""
        return "\n".join(d.render(self.sources) for d in self.diagnostics.sorted())


def check_file(path: str | Path, schedule: str | None = None, text: str | None = None,
               given: dict[Path, str] | None = None, parse=None, sdf_cache=None) -> FrontEndResult:
    """Parse, check and analyse a model file and its imports.

    ``schedule`` overrides every dataflow's schedule kind (``sas`` or
    ``min-buffer``). ``text``, if given, is read instead of the root file
    (its imports are still files, relative to ``path``). ``given`` maps
    other files to the texts read instead of them (an editor's unsaved
    imports); ``parse`` stands for the parser (see :func:`load`);
    ``sdf_cache`` (an :class:`~easylab.analysis.sdf.AnalysisCache`) answers
    for dataflows whose SDF graph it has analysed before.

    Raises OSError (FileNotFoundError, UnicodeDecodeError as ValueError) only
    for the root file itself; every problem inside a model is a diagnostic.
    """
    texts = dict(given or {})
    if text is not None:
        texts[Path(path)] = text
    sources = SourceCache(texts)
    diags = Diagnostics()
    loaded = load(Path(path), sources, diags) if parse is None else load(Path(path), sources, diags, parse)
    model = None
    # After a syntax error anywhere the namespace is partial: checking it
    # would only add misleading follow-on errors.
    if loaded is not None and not diags.has_errors:
        model = check(loaded.modules, loaded.root, diags)
    timing = None
    if model is not None:
        analyze_model(model, diags, schedule, sdf_cache)
        if not diags.has_errors:
            timing = compute_timing(model, diags)
    ok = not diags.has_errors
    return FrontEndResult(model if ok else None, diags, sources, timing if ok else None)


def lower_file(path: str | Path, schedule: str | None = None, text: str | None = None):
    """Front end, analyses and lowering: (IR program or None, FrontEndResult)."""
    result = check_file(path, schedule, text)
    if result.model is None:
        return None, result
    return lower(result.model, result.timing), result


def model_files(path: Path, program: Program | None) -> list[Path]:
    """The files a model depends on: itself, its imports, the impl files of
    its actors and the handler files of its devices."""
    files = [path]
    loaded = load(path, SourceCache(), Diagnostics())
    if loaded is not None:
        for module in loaded.modules:
            name = module.file
            files.append(library_path(name[1:-1]) if name.startswith("<") and name.endswith(">") else Path(name))
    if program is not None:
        files += [Path(s.impl) for s in program.specs if s.impl]
        files += [Path(f) for d in program.devices for f in d.handlers.values()]
        files += [Path(d.chip) for d in program.devices if d.chip]
    return list(dict.fromkeys(files))
