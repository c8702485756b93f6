"""Reading a model file and everything it imports.

``import std`` names a library shipped with the tool (``stdlib/std.elab``);
``import "lib/x.elab"`` a file relative to the importing one. Each file is
parsed once however often it is imported; a cycle of imports is reported
at the import that closes it.
"""

from __future__ import annotations

from dataclasses import dataclass
from importlib import resources
from pathlib import Path

from . import ast
from .parser import parse_text
from ..core.source import Diagnostics, ModelError, SourceCache, Span, did_you_mean

LIBRARIES = ("std",)


def library_path(name: str) -> Path:
    """The file behind ``import NAME`` for a shipped library."""
    return Path(str(resources.files("easylab.stdlib").joinpath(f"{name}.elab")))


def module_dir(file: Path) -> Path:
    """The folder a module's relative paths (impl files) start from; for a
    shipped library (``<std>``), its installed folder."""
    if file.name.startswith("<") and file.name.endswith(">"):
        return library_path(file.name[1:-1]).parent
    return file.parent


@dataclass
class LoadedModel:
    """The root module and every module it imports, in load order."""

    root: ast.Module
    modules: list[ast.Module]


def load(path: Path, sources: SourceCache, diags: Diagnostics, parse=parse_text) -> LoadedModel | None:
    """Parse ``path`` and its imports; syntax errors go to ``diags``.
    ``parse(text, name)`` stands for :func:`parse_text` (the language
    server's parser, which re-parses only what an edit changed)."""
    loaded: dict[Path, ast.Module | None] = {}
    order: list[ast.Module] = []
    root = _load_file(path, sources, diags, loaded, order, stack=[], importer=None, parse=parse)
    if root is None:
        return None
    return LoadedModel(root, order)


def _display_name(path: Path) -> str:
    try:
        return str(path.resolve().relative_to(Path.cwd().resolve()))
    except ValueError:
        return str(path)


def as_if_read(text: str) -> str:
    """A model text given in memory as reading its file would give it: the
    byte order mark dropped and line ends ('\\r\\n', a lone '\\r') made
    '\\n', so a given text and its file get the same diagnostics."""
    return text.removeprefix("\ufeff").replace("\r\n", "\n").replace("\r", "\n")


def _load_file(path: Path, sources: SourceCache, diags: Diagnostics,
               loaded: dict, order: list, stack: list[Path], importer: ast.Import | None, parse=parse_text):
    key = path.resolve()
    if key in stack:
        cycle = " -> ".join(p.name for p in stack[stack.index(key):] + [key])
        diags.error(importer.span, f"import cycle: {cycle}", "remove one of these imports")
        return None
    if key in loaded:
        return loaded[key]
    name = _display_name(path) if importer is None or not _is_library(key) else f"<{key.stem}>"
    try:
        text = sources.given(path)
        if text is None:
            _check_readable(path)
            text = path.read_text(encoding="utf-8-sig")  # an editor's byte order mark is no error
        else:
            text = as_if_read(text)
        if "\0" in text:  # valid UTF-8, but no text file has NUL bytes
            raise UnicodeDecodeError("utf-8", text.encode("utf-8"), text.index("\0"), text.index("\0") + 1,
                                     "a NUL byte: a binary file, not a model")
    except FileNotFoundError:
        if importer is None:
            raise
        diags.error(importer.span, f"imported file '{importer.target}' not found (looked at {path})")
        loaded[key] = None
        return None
    except (OSError, UnicodeDecodeError) as err:
        if importer is None:
            raise
        diags.error(importer.span, f"cannot read imported file '{importer.target}': {err}")
        loaded[key] = None
        return None
    sources.add(name, text)
    try:
        module = parse(text, name)
    except ModelError as err:
        for d in err.diagnostics:
            diags.add(d)
        loaded[key] = None
        return None
    loaded[key] = module
    stack.append(key)
    for imp in module.imports:
        if imp.is_library:
            if imp.target not in LIBRARIES:
                diags.error(imp.span, f"unknown library '{imp.target}'",
                            did_you_mean(imp.target, LIBRARIES) or
                            "import a file by its path in quotes: import \"lib/actors.elab\"")
                continue
            target = library_path(imp.target)
        else:
            target = path.parent / imp.target
        _load_file(target, sources, diags, loaded, order, stack, imp, parse)
    stack.pop()
    order.append(module)
    return module


MAX_MODEL_BYTES = 16 * 1024 * 1024


class ModelFileError(OSError):
    """A path that is not a model file one can read: a device, a pipe, a
    file larger than MAX_MODEL_BYTES."""


def _check_readable(path: Path) -> None:
    import stat

    info = path.stat()  # FileNotFoundError passes through
    if stat.S_ISDIR(info.st_mode):
        raise IsADirectoryError(21, "is a directory", str(path))
    if not stat.S_ISREG(info.st_mode):
        raise ModelFileError(f"not a regular file")
    if info.st_size > MAX_MODEL_BYTES:
        raise ModelFileError(f"{info.st_size} bytes: larger than a model file may be ({MAX_MODEL_BYTES} bytes)")


def _is_library(path: Path) -> bool:
    return any(path == library_path(name).resolve() for name in LIBRARIES)


def root_span(module: ast.Module) -> Span:
    return module.header.span if module.header else Span(module.file, 1, 1, 1, 1)
