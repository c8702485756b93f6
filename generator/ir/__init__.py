"""The IR (docs/ir.md): the one lowered, board-independent program that is
the only contract between the front end and the backends. :mod:`.program`
defines it; :mod:`.lower` makes it from a checked, analysed model."""
