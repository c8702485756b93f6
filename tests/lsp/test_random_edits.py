"""Random edits of the examples, sent to `easylab lsp` as a user's typing
would: the server answers each with diagnostics, never crashes, and its
diagnostics are `easylab check`'s for the same text (same line, column and
message). The edits are the front end's mutations (tests/frontend/
mutations.py), drawn from a seeded generator: the same cases everywhere."""

from __future__ import annotations

import pytest
import pytest_lsp
from pytest_lsp import LanguageClient

from lsp_helpers import EXAMPLES, SERVER, change_file, check_errors, lsp_errors, open_file, start
from mutations import SeededChooser, mutate

pytestmark = pytest.mark.asyncio(loop_scope="module")
EDITS_PER_EXAMPLE = 6


@pytest_lsp.fixture(config=SERVER, scope="module")
async def client(lsp_client: LanguageClient):
    await start(lsp_client)
    yield
    await lsp_client.shutdown_session()


@pytest.mark.parametrize("example", EXAMPLES, ids=lambda p: p.stem)
async def test_random_edits_get_the_diagnostics_of_easylab_check(client: LanguageClient, example, tmp_path):
    # a copy beside the example's own imports and driver files
    path = example.parent / f".lsp_edit_{example.stem}.elab"
    original = example.read_text(encoding="utf-8")
    choose = SeededChooser(sum(map(ord, example.name)))
    try:
        assert await open_file(client, path, original) == []
        for _ in range(EDITS_PER_EXAMPLE):
            text = mutate(original, choose)
            diagnostics = await change_file(client, path, text)
            path.write_text(text, encoding="utf-8", newline="")
            assert lsp_errors(diagnostics) == check_errors(path), text
    finally:
        path.unlink(missing_ok=True)
