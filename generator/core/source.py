"""Source positions and diagnostics.

Every AST node carries a :class:`Span`; every error the front end reports is a
:class:`Diagnostic` rendered as ``file:line:col: error: message`` followed by
the source line and a caret under the span, as compilers do.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path


@dataclass(frozen=True)
class Span:
    """A region of a source file; lines and columns count from 1."""

    file: str
    line: int
    column: int
    end_line: int
    end_column: int

    def __str__(self) -> str:
        return f"{self.file}:{self.line}:{self.column}"

    @staticmethod
    def unknown(file: str = "<unknown>") -> "Span":
        return Span(file, 1, 1, 1, 1)


@dataclass(frozen=True)
class Diagnostic:
    """One error (or note) at a source position, with an optional hint."""

    span: Span
    message: str
    hint: str | None = None
    severity: str = "error"
    notes: tuple["Diagnostic", ...] = ()

    def render(self, sources: "SourceCache") -> str:
        """Format as ``file:line:col: error: message`` plus the line and caret."""
        lines = [f"{self.span}: {self.severity}: {self.message}"]
        lines.extend(sources.excerpt(self.span))
        if self.hint:
            lines.append(f"  hint: {self.hint}")
        for note in self.notes:
            lines.append(note.render(sources))
        return "\n".join(lines)


class SourceCache:
    """Keeps the text of every file read, to quote lines in diagnostics."""

    def __init__(self, given: dict[Path, str] | None = None) -> None:
        self._texts: dict[str, list[str]] = {}
        # Texts that stand for files, by resolved path (a model sent to a
        # running interpreter, read instead of the file on disk).
        self._given = {Path(k).resolve(): v for k, v in (given or {}).items()}

    def given(self, path: Path) -> str | None:
        """The text given for the file at ``path``, if any."""
        return self._given.get(path.resolve())

    def add(self, name: str, text: str) -> None:
        # Lines end at '\n' only, as for the lexer (splitlines() would also
        # split at form feeds and other separators and shift every line).
        self._texts[name] = [line.removesuffix("\r") for line in text.split("\n")]

    def read(self, path: Path) -> str:
        """Read a model file as UTF-8 and remember it under its display name."""
        text = path.read_text(encoding="utf-8")
        self.add(str(path), text)
        return text

    def excerpt(self, span: Span) -> list[str]:
        lines = self._texts.get(span.file)
        if not lines or not 1 <= span.line <= len(lines):
            return []
        text = lines[span.line - 1].expandtabs(1)
        width = 1
        if span.end_line == span.line and span.end_column > span.column:
            width = span.end_column - span.column
        elif span.end_line > span.line:
            width = max(1, len(text) - span.column + 1)
        gutter = f"{span.line:5d} | "
        return [gutter + text, " " * (len(gutter) + span.column - 1) + "^" + "~" * (width - 1)]


@dataclass
class Diagnostics:
    """Collects diagnostics so that one run reports every error it finds."""

    items: list[Diagnostic] = field(default_factory=list)

    def error(self, span: Span, message: str, hint: str | None = None,
              notes: tuple[Diagnostic, ...] = ()) -> None:
        self.items.append(Diagnostic(span, message, hint, "error", notes))

    def add(self, diagnostic: Diagnostic) -> None:
        self.items.append(diagnostic)

    def extend(self, other: "Diagnostics") -> None:
        self.items.extend(other.items)

    @property
    def has_errors(self) -> bool:
        return any(d.severity == "error" for d in self.items)

    def sorted(self) -> list[Diagnostic]:
        seen: set[tuple] = set()
        unique = []
        for d in sorted(self.items, key=lambda d: (d.span.file, d.span.line, d.span.column)):
            key = (d.span, d.message)
            if key not in seen:
                seen.add(key)
                unique.append(d)
        return unique


class ModelError(Exception):
    """Raised when a model cannot be processed further; carries its diagnostics."""

    def __init__(self, diagnostics: list[Diagnostic]):
        super().__init__("\n".join(f"{d.span}: {d.message}" for d in diagnostics))
        self.diagnostics = diagnostics


def note(span: Span, message: str) -> Diagnostic:
    """A note attached to an error, pointing at a related place."""
    return Diagnostic(span, message, severity="note")


def closest(name: str, candidates) -> str | None:
    """The candidate a misspelt name most likely means, or None."""
    import difflib

    matches = difflib.get_close_matches(name, sorted(set(candidates)), n=1, cutoff=0.6)
    return matches[0] if matches else None


def did_you_mean(name: str, candidates) -> str | None:
    """A ``did you mean 'x'?`` hint for a misspelt name, or None."""
    match = closest(name, candidates)
    return f"did you mean '{match}'?" if match else None
