"""The VS Code extension's TextMate grammar beside the model language's own
lexer: tokens from both, for tests/editors/."""

from __future__ import annotations

import fcntl
import functools
import json
import subprocess
from pathlib import Path

import lark

from easylab.frontend.grammar import grammar_text
from easylab.frontend.inline_c import blank_inline_c

ROOT = Path(__file__).resolve().parents[2]
EXTENSION = ROOT / "editors" / "vscode"


def npm_install() -> None:
    """The extension's packages as package-lock.json pins them (`make
    vscode-packages`: once, then whenever the lock file changes), under a
    lock: test processes side by side must not install over each other."""
    (ROOT / "build").mkdir(exist_ok=True)
    with open(ROOT / "build" / ".vscode-packages.lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        proc = subprocess.run(["make", "-s", "vscode-packages"], cwd=ROOT, capture_output=True, text=True,
                              timeout=600)
        assert proc.returncode == 0, proc.stdout + proc.stderr


def textmate_tokens(texts: list[str]) -> list[list[tuple[int, int, int, list[str]]]]:
    """Per text, its tokens [line, start, end, scopes] (from 0) as VS Code's
    TextMate engine gives them (editors/vscode/test/tokenize.js)."""
    npm_install()
    proc = subprocess.run(["node", str(EXTENSION / "test" / "tokenize.js")], input=json.dumps(texts),
                          capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stderr
    return json.loads(proc.stdout)


_COMMENTS: list[lark.Token] = []


@functools.lru_cache(maxsize=1)
def _lark_parser() -> lark.Lark:
    """The language's parser keeping every token; comments go to _COMMENTS."""
    return lark.Lark(grammar_text(), parser="lalr", lexer="contextual", keep_all_tokens=True,
                     lexer_callbacks={"COMMENT": _COMMENTS.append, "BLOCK_COMMENT": _COMMENTS.append})


def lark_tokens(text: str) -> list[lark.Token] | None:
    """Every token the model language's contextual lexer finds in ``text``
    (inline C blanked, as the front end does), comments included, lines and
    columns from 1; None for a text that does not parse."""
    _COMMENTS.clear()
    try:
        blanked, _ = blank_inline_c(text, "<text>")
        tree = _lark_parser().parse(blanked)
    except Exception:  # a model that is meant to be wrong
        return None
    tokens = list(tree.scan_values(lambda v: isinstance(v, lark.Token))) + _COMMENTS
    return sorted(tokens, key=lambda t: (t.line, t.column))
