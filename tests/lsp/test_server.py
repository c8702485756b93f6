"""`easylab lsp` end to end: a real client starts `python -m easylab lsp`
and talks to it over stdio about the examples and about a model spread
over two files."""

from __future__ import annotations

import pytest
import pytest_lsp
from lsprotocol import types as lsp
from pytest_lsp import LanguageClient

from lsp_helpers import (EXAMPLES, ROOT, SERVER, change_file, check_errors, diagnostics_of, doc, lsp_errors,
                         open_file, position_of, start)

pytestmark = pytest.mark.asyncio(loop_scope="module")

BLINK = ROOT / "examples" / "blink.elab"
LIB = """\
// Shared parts of the two-file model.
import std

param gain: int16 = 500 range 0..1000 unit "1/1000"

actor type Twice<T: number>() {
    in  x: T
    out y: T
    step {{ y = x; }}
}
"""
MAIN = """\
model two "a model in two files"
import std
import "lib.elab"

var out: int16
device sensor: AnalogIn(channel = 0)

dataflow Flow {
    conv = Cast<uint16, int16>()
    scaled = Gain<int16>(k = gain)
    twice = Twice<int16>()
    sensor.value -> conv.x
    conv.y -> scaled.x
    scaled.y -> twice.x
    twice.y -> out
}

task main period 10 ms { run Flow }
"""


@pytest_lsp.fixture(config=SERVER, scope="module")
async def client(lsp_client: LanguageClient):
    await start(lsp_client)
    yield
    await lsp_client.shutdown_session()


@pytest.fixture(scope="module")
def two_files(tmp_path_factory):
    folder = tmp_path_factory.mktemp("two")
    (folder / "lib.elab").write_text(LIB)
    (folder / "main.elab").write_text(MAIN)
    return folder / "main.elab", folder / "lib.elab"


async def test_every_example_opens_without_diagnostics(client: LanguageClient):
    for path in EXAMPLES:
        assert await open_file(client, path) == [], path


async def test_an_edit_gets_the_checkers_errors_with_their_ranges(client: LanguageClient, tmp_path):
    path = tmp_path / "blink.elab"
    text = BLINK.read_text()
    path.write_text(text)
    assert await open_file(client, path, text) == []
    broken = text.replace("SquareWave(half_period = half_period)", "SquareWave(half_period = half_perod)")
    diagnostics = await change_file(client, path, broken)
    path.write_text(broken)
    assert lsp_errors(diagnostics) == check_errors(path) != []
    (d,) = diagnostics
    start_at = position_of(broken, "half_perod)")
    assert d.range == lsp.Range(start_at, lsp.Position(start_at.line, start_at.character + len("half_perod")))
    assert "did you mean 'half_period'?" in d.message
    # the state is kept: undoing the edit clears the error
    assert await change_file(client, path, text) == []


async def test_a_syntax_error_in_an_import_is_published_for_the_imported_file(client: LanguageClient,
                                                                              two_files):
    main, lib = two_files
    assert await open_file(client, main) == []
    main_version = max(v for u, v in client.published if u == main.as_uri())
    assert await open_file(client, lib) == []
    broken = LIB.replace("param gain: int16", "param gain int16")
    try:
        main_published = len(client.published.get((main.as_uri(), main_version), ()))
        (error,) = await change_file(client, lib, broken)
        assert error.range.start == position_of(broken, "int16") and "expected ':'" in error.message
        # main.elab, which imports it, is checked again: the error is in lib.elab, not in main.elab
        assert await diagnostics_of(client, main.as_uri(), main_version, main_published) == []
    finally:
        assert await change_file(client, lib, LIB) == []


async def test_document_symbols_list_devices_dataflows_and_their_instances(client: LanguageClient, two_files):
    main, _ = two_files
    await open_file(client, main)
    symbols = await client.text_document_document_symbol_async(lsp.DocumentSymbolParams(doc(main)))
    by_name = {s.name: s for s in symbols}
    assert {"out", "sensor", "Flow", "main"} <= set(by_name)
    assert by_name["sensor"].detail == "device" and by_name["main"].detail == "task"
    assert [c.name for c in by_name["Flow"].children] == ["conv", "scaled", "twice"]
    chart_model = ROOT / "examples" / "pneumatic_cylinder.elab"
    await open_file(client, chart_model)
    symbols = await client.text_document_document_symbol_async(lsp.DocumentSymbolParams(doc(chart_model)))
    charts = [s for s in symbols if s.detail == "chart"]
    assert charts and all(c.children and all(s.detail == "step" for s in c.children) for c in charts)


async def test_definition_goes_into_the_imported_file_and_into_std(client: LanguageClient, two_files):
    main, lib = two_files
    await open_file(client, main)
    found = await client.text_document_definition_async(lsp.DefinitionParams(
        doc(main), position_of(MAIN, "Twice<", 1)))
    assert found.uri == lib.as_uri() and found.range.start == position_of(LIB, "Twice")
    found = await client.text_document_definition_async(lsp.DefinitionParams(
        doc(main), position_of(MAIN, "gain)", 1)))
    assert found.uri == lib.as_uri() and found.range.start == position_of(LIB, "gain:")
    found = await client.text_document_definition_async(lsp.DefinitionParams(
        doc(main), position_of(MAIN, "Gain<", 1)))
    assert found.uri.endswith("/stdlib/std.elab")
    std_text = (ROOT / "generator" / "stdlib" / "std.elab").read_text()
    assert found.range.start == position_of(std_text, "Gain<")
    # a port through its instance: twice.x is Twice's port x
    found = await client.text_document_definition_async(lsp.DefinitionParams(
        doc(main), position_of(MAIN, "twice.x", 6)))
    assert found.uri == lib.as_uri() and found.range.start == position_of(LIB, "x: T")


async def test_references_span_both_files(client: LanguageClient, two_files):
    main, lib = two_files
    await open_file(client, main)
    found = await client.text_document_references_async(lsp.ReferenceParams(
        text_document=doc(main), position=position_of(MAIN, "gain)"),
        context=lsp.ReferenceContext(include_declaration=True)))
    assert sorted((loc.uri, loc.range.start.line) for loc in found) == [(lib.as_uri(), 3), (main.as_uri(), 9)]


async def test_rename_edits_every_file_and_refuses_a_collision(client: LanguageClient, two_files):
    main, lib = two_files
    await open_file(client, main)
    edit = await client.text_document_rename_async(lsp.RenameParams(doc(main), position_of(MAIN, "gain)"), "k_gain"))
    assert {uri: len(edits) for uri, edits in edit.changes.items()} == {main.as_uri(): 1, lib.as_uri(): 1}
    assert all(e.new_text == "k_gain" for edits in edit.changes.values() for e in edits)
    renamed = {main: MAIN, lib: LIB}
    for path, text in renamed.items():
        (e,) = edit.changes[path.as_uri()]
        start_at = e.range.start
        assert text.split("\n")[start_at.line][start_at.character:e.range.end.character] == "gain"
    with pytest.raises(Exception, match="already a name"):
        await client.text_document_rename_async(lsp.RenameParams(doc(main), position_of(MAIN, "gain)"), "sensor"))
    with pytest.raises(Exception, match="library"):
        await client.text_document_rename_async(lsp.RenameParams(doc(main), position_of(MAIN, "Gain<"), "G"))
    # an instance: renamed in its dataflow only
    edit = await client.text_document_rename_async(lsp.RenameParams(doc(main), position_of(MAIN, "twice ="), "dbl"))
    assert len(edit.changes[main.as_uri()]) == 3
    with pytest.raises(Exception, match="already a name"):
        await client.text_document_rename_async(lsp.RenameParams(doc(main), position_of(MAIN, "twice ="), "scaled"))


async def test_hover_tells_types_ranges_ports_and_drivers(client: LanguageClient, two_files):
    main, _ = two_files
    await open_file(client, main)

    async def hover(needle, offset=0):
        found = await client.text_document_hover_async(lsp.HoverParams(doc(main), position_of(MAIN, needle, offset)))
        return found.contents.value

    text = await hover("gain)")
    assert "**param** `gain`" in text and "int16" in text and "0..1000" in text and "1/1000" in text
    assert "500" in text
    text = await hover("twice =")
    assert "Twice<int16>" in text and "in `x`: int16, rate 1" in text
    text = await hover("sensor.value")
    assert "`sensor`: driver `" in text and "out value: uint16" in text and "adc[0]" in text
    text = await hover("Gain<", 1)  # std's declaration and its documentation comment
    assert "**actor type** `Gain`" in text and "actor type Gain<T: number>(k: int32 = 1000)" in text
    assert "y = x * k / 1000" in text


async def test_completion_offers_types_keywords_edge_ends_and_board_pins(client: LanguageClient, two_files,
                                                                          tmp_path):
    main, _ = two_files
    await open_file(client, main)

    async def labels(text, needle, offset):
        found = await client.text_document_completion_async(lsp.CompletionParams(
            doc(main), position_of(text, needle, offset)))
        return {i.label: i for i in found.items}

    top = await labels(MAIN, "var out", 0)
    assert {"dataflow", "task", "device"} <= set(top)
    assert top["Gain"].insert_text.startswith("Gain<${1:T}>(k = ")
    assert "AnalogIn" in top and "Twice" in top
    before = await labels(MAIN, "    scaled.y", 4)
    after = await labels(MAIN, "-> twice.x", 3)
    assert "scaled.y" in before and "sensor.value" in before and "gain" in before and "twice.x" not in before
    assert "twice.x" in after and "out" in after and "scaled.y" not in after and "gain" not in after
    board = tmp_path / "board.elab"
    text = 'model b\nimport std\nnode n board avr mcu atmega328p\ndevice led: DigitalOut(pin = "PB5") on n\n'
    await open_file(client, board, text)
    # after `pin["` the pins of the MCU the model's node names
    await change_file(client, board, text + 'debug on pin["')
    found = await client.text_document_completion_async(lsp.CompletionParams(doc(board), lsp.Position(4, 14)))
    assert {"PB5", "PD2"} <= {i.label for i in found.items}
    found = await client.text_document_completion_async(lsp.CompletionParams(doc(board), lsp.Position(2, 0)))
    assert "uart0" in {i.label for i in found.items}


async def test_quick_fixes_add_import_std_and_correct_a_misspelling(client: LanguageClient, tmp_path):
    path = tmp_path / "fix.elab"
    text = BLINK.read_text().replace("import std\n", "")
    diagnostics = await open_file(client, path, text)
    unknown = next(d for d in diagnostics if "DigitalOut" in d.message)
    actions = await client.text_document_code_action_async(lsp.CodeActionParams(
        doc(path), unknown.range, lsp.CodeActionContext([unknown])))
    (action,) = [a for a in actions if a.title == "Add 'import std'"]
    (edit,) = action.edit.changes[path.as_uri()]
    assert edit.new_text == "import std\n" and edit.range.start == lsp.Position(4, 0)
    fixed = _apply(text, edit)
    assert fixed == BLINK.read_text()
    misspelt = fixed.replace("wave.y -> led.level", "wave.y -> lde.level")
    (d,) = await change_file(client, path, misspelt)
    actions = await client.text_document_code_action_async(lsp.CodeActionParams(
        doc(path), d.range, lsp.CodeActionContext([d])))
    (action,) = actions
    (edit,) = action.edit.changes[path.as_uri()]
    assert action.title == "Change 'lde' to 'led'" and _apply(misspelt, edit) == fixed


async def test_formatting_gives_the_formatters_layout(client: LanguageClient, tmp_path):
    from easylab.frontend.format import format_text

    path = tmp_path / "fmt.elab"
    text = BLINK.read_text().replace("task main period 1 ms { run Blink }", "task   main period 1 ms {run Blink}")
    await open_file(client, path, text)
    edits = await client.text_document_formatting_async(lsp.DocumentFormattingParams(
        doc(path), lsp.FormattingOptions(tab_size=4, insert_spaces=True)))
    (edit,) = edits
    assert edit.new_text == format_text(text) == BLINK.read_text()


def _apply(text: str, edit: lsp.TextEdit) -> str:
    lines = text.split("\n")
    offset = lambda p: sum(len(line) + 1 for line in lines[:p.line]) + p.character  # noqa: E731
    return text[:offset(edit.range.start)] + edit.new_text + text[offset(edit.range.end):]
