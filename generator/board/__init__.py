"""Boards: the contract every board implements (:mod:`.contract`), finding
and loading them (:mod:`.registry`), and what several boards share: their
descriptions, resource claims against a part's tables, a gcc-style build,
and the simulators' tables."""
