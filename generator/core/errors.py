"""Errors that stages after the front end report as one clear message."""


class BuildError(Exception):
    """A build that cannot go on: the message is one clear line (or a
    compiler's output, or a list of problems each at its source line)."""
