"""The language server's model of the open files: their texts, the model
each one roots, its diagnostics and its name index, kept across edits.

File names: the front end names a file as ``easylab check`` shows it
(relative to the working folder where it can, ``<std>`` for the shipped
library); the server speaks of URIs. :func:`file_path` goes from the one
to the other.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from urllib.parse import unquote, urlparse

from ..analysis.sdf import AnalysisCache
from ..core.collector import collect_all, collect_young, cycle_collection_paused
from ..core.source import Diagnostic, Span
from ..frontend import ast
from ..frontend.loader import LIBRARIES, as_if_read, library_path
from ..pipeline import FrontEndResult, check_file
from .incremental import ChunkedParser
from .index import ModelIndex


def uri_to_path(uri: str) -> Path:
    """The file a ``file://`` URI names."""
    return Path(unquote(urlparse(uri).path))


def path_to_uri(path: Path) -> str:
    """The ``file://`` URI of a file."""
    return path.resolve().as_uri()


def file_path(name: str) -> Path:
    """The file behind a front-end file name (``<std>`` is the shipped library)."""
    if name.startswith("<") and name.endswith(">") and name[1:-1] in LIBRARIES:
        return library_path(name[1:-1])
    return Path(name).resolve()


@dataclass
class Analysis:
    """What one check of a model gave: its result, its modules and their index."""

    root: Path
    result: FrontEndResult
    modules: list[ast.Module]

    @cached_property
    def index(self) -> ModelIndex:
        """The modules' names, built when a request first needs them:
        diagnostics do not, so an edit's diagnostics do not wait for it."""
        return ModelIndex(self.modules)

    def file_name(self, path: Path) -> str | None:
        """The front end's name of a file of this model."""
        key = path.resolve()
        for module in self.modules:
            if file_path(module.file) == key:
                return module.file
        return None

    def module(self, path: Path) -> ast.Module | None:
        name = self.file_name(path)
        return next((m for m in self.modules if m.file == name), None)

    def diagnostics_by_file(self) -> dict[Path, list[Diagnostic]]:
        """The model's diagnostics, by the file they are in."""
        out: dict[Path, list[Diagnostic]] = {file_path(m.file): [] for m in self.modules}
        out.setdefault(self.root.resolve(), [])
        for d in self.result.diagnostics.sorted():
            out.setdefault(file_path(d.span.file), []).append(d)
        return out


class Workspace:
    """The open files and the latest analysis of each model they root."""

    def __init__(self) -> None:
        self.texts: dict[Path, str] = {}
        self.analyses: dict[Path, Analysis] = {}
        self.parser = ChunkedParser()
        # Dataflows an edit left alone keep their SDF analysis.
        self.sdf_cache = AnalysisCache()
        self._modules_seen: dict[Path, list[ast.Module]] = {}

    def open(self, path: Path, text: str) -> Analysis:
        """A file opened or changed: re-check it (and, kept, the models
        that import it)."""
        self.texts[path.resolve()] = as_if_read(text)  # lines as the front end counts them
        return self.analyse(path)

    def close(self, path: Path) -> None:
        self.texts.pop(path.resolve(), None)
        self.analyses.pop(path.resolve(), None)

    def analyse(self, path: Path) -> Analysis:
        """Check the model rooted at ``path`` with the open files' texts.

        The analysis it replaces is garbage from here on for the workspace
        (whoever still holds it keeps it alive): it was built while the
        cycle collector was paused and collected once, young, so a young
        collection frees it now; the new one is built the same way. The
        collector's own schedule would instead move each model to the
        oldest generation and then scan everything the server holds (the
        parsed files included) about once per edit on a large model. A
        model checked for the first time ends with a full collection, which
        puts its parsed files, long-lived, where young collections do not
        look (else the first edit would move them there, and pay for it).
        """
        key = path.resolve()
        first = self.analyses.pop(key, None) is None  # holding it would keep it alive
        collect_young()
        with cycle_collection_paused():
            analysis = self._check(path, key)
        self.analyses[key] = analysis
        if first:
            collect_all()
        return analysis

    def _check(self, path: Path, key: Path) -> Analysis:
        modules: list[ast.Module] = []

        def parse(text: str, name: str) -> ast.Module:
            module = self.parser(text, name)
            modules.append(module)
            return module

        result = check_file(path, given=self.texts, parse=parse, sdf_cache=self.sdf_cache)
        # A file that does not parse keeps the index of its last good text,
        # so that navigation still works while it is being edited.
        if result.model is None and not modules:
            modules = list(self._modules_seen.get(key, []))
        else:
            previous = {m.file: m for m in self._modules_seen.get(key, [])}
            parsed = {m.file for m in modules}
            modules += [m for name, m in previous.items() if name not in parsed]
            self._modules_seen[key] = modules
        return Analysis(path, result, modules)

    def dependents(self, path: Path) -> list[Path]:
        """The open models other than ``path`` whose files include ``path``."""
        key = path.resolve()
        return [root for root, a in self.analyses.items()
                if root != key and any(file_path(m.file) == key for m in a.modules)]

    def analysis_for(self, path: Path) -> Analysis | None:
        """The analysis that best knows a file: its own model's, else that
        of an open model that imports it."""
        key = path.resolve()
        if key in self.analyses:
            return self.analyses[key]
        for a in self.analyses.values():
            if a.file_name(key) is not None:
                return a
        return None

    def line_text(self, path: Path, line: int) -> str:
        """A line of a file (1-based), from the editor's text where open."""
        text = self.text(path)
        lines = text.split("\n")
        return lines[line - 1] if 1 <= line <= len(lines) else ""

    def text(self, path: Path) -> str:
        key = path.resolve()
        if key in self.texts:
            return self.texts[key]
        try:
            return key.read_text(encoding="utf-8-sig")
        except (OSError, UnicodeDecodeError):
            return ""

    def source(self, span: Span) -> str:
        """The text a span covers."""
        lines = self.text(file_path(span.file)).split("\n")[span.line - 1:span.end_line]
        if not lines:
            return ""
        if len(lines) == 1:
            return lines[0][span.column - 1:span.end_column - 1]
        return "\n".join([lines[0][span.column - 1:], *lines[1:-1], lines[-1][:span.end_column - 1]])
