"""Shared helpers of the language server's tests: a real client (pytest-lsp)
talking to `python -m easylab lsp` over stdio, and `easylab check`'s
diagnostics in the same terms for comparison."""

from __future__ import annotations

import asyncio
import itertools
import re
import subprocess
import sys
from pathlib import Path

from lsprotocol import types as lsp
from pytest_lsp import ClientServerConfig, LanguageClient
from pytest_lsp.client import make_test_lsp_client

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "tests" / "frontend")]  # mutations.py
EXAMPLES = sorted(p for p in (ROOT / "examples").rglob("*.elab") if not p.name.startswith("."))



def _client() -> LanguageClient:
    """pytest-lsp's client, also keeping every diagnostics notification by
    (uri, version): waiting for the next notification could miss one that
    arrives together with another."""
    client = make_test_lsp_client()
    client.published = {}
    features = client.protocol.fm.features
    keep_latest = features[lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS]

    def publish(params: lsp.PublishDiagnosticsParams):
        client.published.setdefault((params.uri, params.version), []).append(list(params.diagnostics))
        return keep_latest(params)

    features[lsp.TEXT_DOCUMENT_PUBLISH_DIAGNOSTICS] = publish
    return client


SERVER = ClientServerConfig(server_command=[sys.executable, "-m", "easylab", "lsp"], client_factory=_client)
CHECK_LINE = re.compile(r"^(?P<file>[^\s].*?):(?P<line>\d+):(?P<col>\d+): error: (?P<message>.*)$")


async def start(client: LanguageClient) -> None:
    """The protocol's opening handshake."""
    await client.initialize_session(lsp.InitializeParams(
        capabilities=lsp.ClientCapabilities(), root_uri=ROOT.as_uri()))


_versions = itertools.count(1)  # every text sent has a version of its own


async def open_file(client: LanguageClient, path: Path, text: str | None = None) -> list[lsp.Diagnostic]:
    """Open a file in the server; the diagnostics it publishes for it."""
    uri, version = path.resolve().as_uri(), next(_versions)
    client.text_document_did_open(lsp.DidOpenTextDocumentParams(lsp.TextDocumentItem(
        uri=uri, language_id="elab", version=version,
        text=path.read_text(encoding="utf-8") if text is None else text)))
    return await diagnostics_of(client, uri, version)


async def change_file(client: LanguageClient, path: Path, text: str) -> list[lsp.Diagnostic]:
    """Replace an open file's text (full sync); the diagnostics published for it."""
    uri, version = path.resolve().as_uri(), next(_versions)
    client.text_document_did_change(lsp.DidChangeTextDocumentParams(
        lsp.VersionedTextDocumentIdentifier(uri=uri, version=version),
        [lsp.TextDocumentContentChangeWholeDocument(text)]))
    return await diagnostics_of(client, uri, version)


async def diagnostics_of(client: LanguageClient, uri: str, version: int, index: int = 0) -> list[lsp.Diagnostic]:
    """The diagnostics published for that version of ``uri``'s text (the
    ``index``-th publication of it: a file is published again when a file
    it imports changes)."""
    async def published():
        while len(client.published.get((uri, version), ())) <= index:
            await asyncio.sleep(0.005)
        return client.published[(uri, version)][index]

    return await asyncio.wait_for(published(), 60)  # a server that never answers fails the test


def doc(path: Path) -> lsp.TextDocumentIdentifier:
    return lsp.TextDocumentIdentifier(path.resolve().as_uri())


def position_of(text: str, needle: str, offset: int = 0, nth: int = 0) -> lsp.Position:
    """The position ``offset`` characters into the ``nth`` occurrence of ``needle``."""
    at = -1
    for _ in range(nth + 1):
        at = text.index(needle, at + 1)
    at += offset
    line = text.count("\n", 0, at)
    return lsp.Position(line, at - (text.rfind("\n", 0, at) + 1))


def lsp_errors(diagnostics: list[lsp.Diagnostic]) -> list[tuple[int, int, str]]:
    """(line, column, message) from 1, as `easylab check` prints them."""
    return sorted({(d.range.start.line + 1, d.range.start.character + 1, d.data["message"]) for d in diagnostics
                   if d.severity == lsp.DiagnosticSeverity.Error})


def check_errors(path: Path) -> list[tuple[int, int, str]]:
    """The errors `easylab check` prints for ``path`` itself (not its imports)."""
    proc = subprocess.run([sys.executable, "-m", "easylab", "check", path.name], cwd=path.parent,
                          capture_output=True, text=True, timeout=120)
    found = []
    for line in proc.stderr.splitlines():
        m = CHECK_LINE.match(line)
        if m and m["file"] == path.name:
            found.append((int(m["line"]), int(m["col"]), m["message"]))
    return sorted(set(found))
