"""``easylab fmt``: lay out model files canonically (docs/language.md,
"Formatting"), in place, to standard output, or only say which would change."""

from __future__ import annotations

import difflib
import os
import sys
import tempfile
from pathlib import Path

from ..core.source import ModelError, SourceCache
from .common import EXIT_MODEL_ERROR, EXIT_OK

STDIN = "-"


def add_parser(sub) -> None:
    """Add the ``fmt`` subcommand to the ``easylab`` command line."""
    p = sub.add_parser(
        "fmt", help="lay out model files canonically",
        description="Rewrite model files (.elab) in the canonical layout of docs/language.md: indentation, "
                    "spacing, blank lines, aligned columns; comments and inline C stay as written, line breaks "
                    "where they are. Files are replaced whole; a file that does not parse is left untouched and "
                    "its error printed (exit status 1). With no FILE, or '-', standard input is formatted to "
                    "standard output.")
    p.add_argument("files", nargs="*", metavar="FILE", help="model files (.elab), '-' for standard input")
    p.add_argument("--check", action="store_true",
                   help="change nothing; name the files whose layout is not canonical (exit status 1 if any)")
    p.add_argument("--diff", action="store_true", help="change nothing; print a unified diff of the changes")
    p.set_defaults(func=cmd_fmt)


def cmd_fmt(args) -> int:
    status = EXIT_OK
    for name in args.files or [STDIN]:
        if not _format_one(name, args):
            status = EXIT_MODEL_ERROR
    return status


def _format_one(name: str, args) -> bool:
    """Format one file as the options say; whether it went well (a file
    already canonical, or rewritten, or formatted to standard output)."""
    from ..frontend.format import FormatError, format_text

    try:
        text = sys.stdin.read() if name == STDIN else Path(name).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as err:
        reason = "not a UTF-8 text file" if isinstance(err, UnicodeDecodeError) else (err.strerror or str(err))
        print(f"easylab: error: {name}: {reason}", file=sys.stderr)
        return False
    shown = "<stdin>" if name == STDIN else name
    try:
        formatted = format_text(text, shown)
    except ModelError as err:
        sources = SourceCache()
        sources.add(shown, text)
        print("\n".join(d.render(sources) for d in err.diagnostics), file=sys.stderr)
        return False
    except FormatError as err:
        print(f"easylab: error: {err}", file=sys.stderr)
        return False
    changed = formatted != text
    if args.diff:
        sys.stdout.writelines(difflib.unified_diff(text.splitlines(True), formatted.splitlines(True),
                                                   f"{shown} (before)", f"{shown} (formatted)"))
    if args.check:
        if changed:
            print(shown)
        return not changed
    if args.diff:
        return True
    if name == STDIN:
        sys.stdout.write(formatted)
    elif changed:
        _replace(Path(name), formatted)
    return True


def _replace(path: Path, text: str) -> None:
    """Write ``text`` to ``path`` whole or not at all (a temporary file in the
    same folder renamed over it), keeping the file's permissions."""
    mode = path.stat().st_mode & 0o7777
    fd, temp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="\n") as out:
            out.write(text)
        os.chmod(temp, mode)
        os.replace(temp, path)
    except BaseException:
        Path(temp).unlink(missing_ok=True)
        raise
