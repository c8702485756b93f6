"""The ``easylab lsp`` subcommand. The language server's packages (pygls,
lsprotocol) are imported only when it runs: every other command starts
without them."""

from __future__ import annotations


def add_parser(sub) -> None:
    """Add the ``lsp`` subcommand to the ``easylab`` command line."""
    p = sub.add_parser("lsp", help="the language server, for editors (over standard input and output)",
                       description="Serve the Language Server Protocol over standard input and output: "
                                   "diagnostics as you type, hover, go to definition, references, rename, "
                                   "symbols, completion, quick fixes and formatting for .elab files "
                                   "(docs/editors.md).")
    p.add_argument("--log", metavar="FILE", help="write the server's log to FILE")
    p.set_defaults(func=cmd_lsp)


def cmd_lsp(args) -> int:
    """`easylab lsp`: serve until the editor closes the connection."""
    from ..lsp.server import serve

    return serve(args.log)
