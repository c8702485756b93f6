"""The language server (``easylab lsp``, docs/editors.md)."""
