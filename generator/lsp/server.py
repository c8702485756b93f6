"""``easylab lsp``: the language server, over standard input and output
(docs/editors.md). It turns the protocol's requests into the workspace's
questions (workspace.py, index.py, features.py, completion.py) and their
answers back into the protocol's types.

Positions: the front end counts lines and columns from 1 in characters,
the protocol from 0 in UTF-16 code units; :func:`to_range` and
:func:`from_position` convert with the line's text.
"""

from __future__ import annotations

import logging
from pathlib import Path

from lsprotocol import types as lsp
from pygls.exceptions import JsonRpcInvalidRequest
from pygls.lsp.server import LanguageServer

from .. import __version__
from ..core.source import Diagnostic, ModelError, Span
from ..frontend.loader import library_path
from . import completion, features
from .workspace import Analysis, Workspace, file_path, path_to_uri, uri_to_path

SOURCE = "easylab"
COMPLETION_KINDS = {"keyword": lsp.CompletionItemKind.Keyword, "actor type": lsp.CompletionItemKind.Class,
                    "device type": lsp.CompletionItemKind.Class, "port": lsp.CompletionItemKind.Field,
                    "data": lsp.CompletionItemKind.Variable, "pin": lsp.CompletionItemKind.Constant,
                    "uart": lsp.CompletionItemKind.Constant, "name": lsp.CompletionItemKind.Reference}
SYMBOL_KINDS = {"device": lsp.SymbolKind.Object, "device type": lsp.SymbolKind.Class,
                "actor type": lsp.SymbolKind.Class, "dataflow": lsp.SymbolKind.Module,
                "chart": lsp.SymbolKind.Module, "task": lsp.SymbolKind.Event, "step": lsp.SymbolKind.EnumMember,
                "actor instance": lsp.SymbolKind.Object, "port": lsp.SymbolKind.Field,
                "param": lsp.SymbolKind.Variable, "var": lsp.SymbolKind.Variable,
                "const": lsp.SymbolKind.Constant, "channel": lsp.SymbolKind.Variable}


class ElabServer(LanguageServer):
    """The server and its workspace (the open files and their models)."""

    def __init__(self) -> None:
        super().__init__("easylab", __version__, text_document_sync_kind=lsp.TextDocumentSyncKind.Full)
        self.models = Workspace()

    # ------------------------------------------------------------ positions

    def to_range(self, span: Span) -> lsp.Range:
        path = file_path(span.file)
        return lsp.Range(self._position(path, span.line, span.column),
                         self._position(path, span.end_line, max(span.end_column, 1)))

    def _position(self, path: Path, line: int, column: int) -> lsp.Position:
        text = self.models.line_text(path, line)[:column - 1]
        return lsp.Position(max(line - 1, 0), len(text.encode("utf-16-le")) // 2)

    def from_position(self, path: Path, position: lsp.Position) -> tuple[int, int]:
        """(line, column) from 1, in characters."""
        text = self.models.line_text(path, position.line + 1)
        units = 0
        for i, ch in enumerate(text):
            if units >= position.character:
                return position.line + 1, i + 1
            units += 2 if ord(ch) > 0xFFFF else 1
        return position.line + 1, len(text) + 1

    def location(self, span: Span) -> lsp.Location:
        return lsp.Location(path_to_uri(file_path(span.file)), self.to_range(span))

    # ------------------------------------------------------------ diagnostics

    def diagnostic(self, d: Diagnostic) -> lsp.Diagnostic:
        message = d.message + (f"\nhint: {d.hint}" if d.hint else "")
        related = [lsp.DiagnosticRelatedInformation(self.location(n.span), n.message) for n in d.notes]
        severity = lsp.DiagnosticSeverity.Error if d.severity == "error" else lsp.DiagnosticSeverity.Information
        return lsp.Diagnostic(self.to_range(d.span), message, severity=severity, source=SOURCE,
                              related_information=related or None,
                              data={"message": d.message, "hint": d.hint})

    def publish(self, analysis: Analysis) -> None:
        """The model's diagnostics, for each of its files (none for a clean file)."""
        for path, diagnostics in analysis.diagnostics_by_file().items():
            if path == library_path("std").resolve():
                continue  # the shipped library is not the user's to fix
            uri = path_to_uri(path)
            # the version lets a client tell these from those of an older text
            version = self.workspace.text_documents[uri].version if uri in self.workspace.text_documents else None
            self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(
                uri, [self.diagnostic(d) for d in diagnostics], version=version))

    def refresh(self, uri: str, text: str) -> None:
        """Check the edited file and the open models that import it. A
        failure of the server itself is published at the file's start, so
        that the editor shows it instead of silently showing nothing."""
        path = uri_to_path(uri)
        try:
            self.publish(self.models.open(path, text))
            for root in self.models.dependents(path):
                self.publish(self.models.analyse(root))
        except Exception as err:  # noqa: BLE001 - the server must go on serving
            logging.exception("checking %s", path)
            start = lsp.Position(0, 0)
            self.text_document_publish_diagnostics(lsp.PublishDiagnosticsParams(uri, [lsp.Diagnostic(
                lsp.Range(start, start), f"easylab lsp: internal error: {type(err).__name__}: {err}",
                severity=lsp.DiagnosticSeverity.Error, source=SOURCE,
                data={"message": f"internal error: {err}", "hint": None})],
                version=self.workspace.text_documents[uri].version if uri in self.workspace.text_documents else None))

    def at(self, uri: str, position: lsp.Position):
        """(analysis, occurrence) under a position, or (analysis, None)."""
        path = uri_to_path(uri)
        analysis = self.models.analysis_for(path)
        if analysis is None:
            return None, None
        name = analysis.file_name(path)
        line, column = self.from_position(path, position)
        return analysis, analysis.index.at(name, line, column) if name else None


server = ElabServer()


@server.feature(lsp.TEXT_DOCUMENT_DID_OPEN)
def did_open(ls: ElabServer, params: lsp.DidOpenTextDocumentParams) -> None:
    ls.refresh(params.text_document.uri, params.text_document.text)


@server.feature(lsp.TEXT_DOCUMENT_DID_CHANGE)
def did_change(ls: ElabServer, params: lsp.DidChangeTextDocumentParams) -> None:
    document = ls.workspace.get_text_document(params.text_document.uri)
    ls.refresh(params.text_document.uri, document.source)


@server.feature(lsp.TEXT_DOCUMENT_DID_CLOSE)
def did_close(ls: ElabServer, params: lsp.DidCloseTextDocumentParams) -> None:
    ls.models.close(uri_to_path(params.text_document.uri))


@server.feature(lsp.TEXT_DOCUMENT_DOCUMENT_SYMBOL)
def document_symbol(ls: ElabServer, params: lsp.DocumentSymbolParams) -> list[lsp.DocumentSymbol]:
    from .index import name_kind, outline

    path = uri_to_path(params.text_document.uri)
    analysis = ls.models.analysis_for(path)
    module = analysis.module(path) if analysis else None
    if module is None:
        return []

    def symbol(node, children=()) -> lsp.DocumentSymbol:
        kind = name_kind(node)
        return lsp.DocumentSymbol(node.name, SYMBOL_KINDS.get(kind, lsp.SymbolKind.Variable), ls.to_range(node.span),
                                  ls.to_range(node.name_span), detail=kind,
                                  children=[symbol(c) for c in children] or None)

    return [symbol(decl, children) for decl, children in outline(module)]


@server.feature(lsp.TEXT_DOCUMENT_DEFINITION)
def definition(ls: ElabServer, params: lsp.DefinitionParams) -> lsp.Location | None:
    _, occ = ls.at(params.text_document.uri, params.position)
    return ls.location(occ.definition.span) if occ else None


@server.feature(lsp.TEXT_DOCUMENT_REFERENCES)
def references(ls: ElabServer, params: lsp.ReferenceParams) -> list[lsp.Location]:
    analysis, occ = ls.at(params.text_document.uri, params.position)
    if occ is None:
        return []
    found = analysis.index.references(occ.definition)
    if not params.context.include_declaration:
        found = [o for o in found if o.span != occ.definition.span]
    return [ls.location(o.span) for o in found]


@server.feature(lsp.TEXT_DOCUMENT_RENAME)
def rename(ls: ElabServer, params: lsp.RenameParams) -> lsp.WorkspaceEdit:
    analysis, occ = ls.at(params.text_document.uri, params.position)
    if occ is None:
        raise JsonRpcInvalidRequest("no name to rename here")
    problem = features.rename_problem(analysis, occ.definition, params.new_name)
    if problem:
        raise JsonRpcInvalidRequest(f"cannot rename: {problem}")
    changes: dict[str, list[lsp.TextEdit]] = {}
    for o in analysis.index.references(occ.definition):
        changes.setdefault(path_to_uri(file_path(o.span.file)), []).append(
            lsp.TextEdit(ls.to_range(o.span), params.new_name))
    return lsp.WorkspaceEdit(changes=changes)


@server.feature(lsp.TEXT_DOCUMENT_HOVER)
def hover(ls: ElabServer, params: lsp.HoverParams) -> lsp.Hover | None:
    analysis, occ = ls.at(params.text_document.uri, params.position)
    if occ is None:
        return None
    text = features.hover_text(ls.models, analysis, occ.definition)
    return lsp.Hover(lsp.MarkupContent(lsp.MarkupKind.Markdown, text), ls.to_range(occ.span))


@server.feature(lsp.TEXT_DOCUMENT_COMPLETION, lsp.CompletionOptions(trigger_characters=[".", "[", '"', ">"]))
def complete(ls: ElabServer, params: lsp.CompletionParams) -> lsp.CompletionList:
    path = uri_to_path(params.text_document.uri)
    analysis = ls.models.analysis_for(path)
    line, column = ls.from_position(path, params.position)
    prefix = ls.models.line_text(path, line)[:column - 1]
    name = analysis.file_name(path) if analysis else None
    items = []
    for c in completion.candidates(analysis, prefix, line, name or ""):
        items.append(lsp.CompletionItem(
            c.label, kind=COMPLETION_KINDS.get(c.kind), detail=c.detail or c.kind,
            insert_text=c.snippet or c.label,
            insert_text_format=lsp.InsertTextFormat.Snippet if c.snippet else lsp.InsertTextFormat.PlainText))
    return lsp.CompletionList(is_incomplete=False, items=items)


@server.feature(lsp.TEXT_DOCUMENT_CODE_ACTION,
                lsp.CodeActionOptions(code_action_kinds=[lsp.CodeActionKind.QuickFix]))
def code_action(ls: ElabServer, params: lsp.CodeActionParams) -> list[lsp.CodeAction]:
    uri = params.text_document.uri
    path = uri_to_path(uri)
    document = ls.workspace.get_text_document(uri)
    actions = []
    for diag in params.context.diagnostics:
        data = diag.data if isinstance(diag.data, dict) else {}
        if diag.source != SOURCE or "message" not in data:
            continue
        covered = _range_text(document.lines, diag.range)
        for fix in features.quick_fixes(ls.models, path, data["message"], data.get("hint"), covered):
            if fix.insert_line is not None:
                at = lsp.Position(fix.insert_line - 1, 0)
                edit = lsp.TextEdit(lsp.Range(at, at), fix.new + "\n")
            else:
                start = covered.index(fix.old)
                edit = lsp.TextEdit(_sub_range(document.lines, diag.range, start, len(fix.old)), fix.new)
            actions.append(lsp.CodeAction(fix.title, kind=lsp.CodeActionKind.QuickFix, diagnostics=[diag],
                                          is_preferred=True, edit=lsp.WorkspaceEdit(changes={uri: [edit]})))
    return actions


def _range_text(lines: list[str], r: lsp.Range) -> str:
    """The text of a single-line range (a multi-line one: its first line's part)."""
    line = lines[r.start.line] if r.start.line < len(lines) else ""
    end = r.end.character if r.end.line == r.start.line else len(line)
    return _utf16_slice(line, r.start.character, end)


def _utf16_slice(line: str, start: int, end: int) -> str:
    return line.encode("utf-16-le")[2 * start:2 * end].decode("utf-16-le", errors="ignore")


def _sub_range(lines: list[str], r: lsp.Range, start: int, length: int) -> lsp.Range:
    """The part of a range's first line ``length`` characters long, ``start`` characters in."""
    line = lines[r.start.line]
    prefix = _utf16_slice(line, 0, r.start.character)
    begin = len((prefix + _range_text(lines, r)[:start]).encode("utf-16-le")) // 2
    middle = _range_text(lines, r)[start:start + length]
    return lsp.Range(lsp.Position(r.start.line, begin),
                     lsp.Position(r.start.line, begin + len(middle.encode("utf-16-le")) // 2))


@server.feature(lsp.TEXT_DOCUMENT_FORMATTING)
def formatting(ls: ElabServer, params: lsp.DocumentFormattingParams) -> list[lsp.TextEdit] | None:
    from ..frontend.format import FormatError, format_text

    document = ls.workspace.get_text_document(params.text_document.uri)
    try:
        formatted = format_text(document.source, str(uri_to_path(params.text_document.uri)))
    except (ModelError, FormatError):
        return None  # the diagnostics say why
    if formatted == document.source:
        return []
    end = lsp.Position(len(document.lines), 0)
    return [lsp.TextEdit(lsp.Range(lsp.Position(0, 0), end), formatted)]


def serve(log: str | None = None) -> int:
    """Serve over standard input and output until the editor closes the
    connection; `log`: a file for the server's log."""
    if log:
        logging.basicConfig(filename=log, level=logging.INFO)
    server.start_io()
    return 0
