"""The checker: names, types, constants, writers, resources and chart structure.

It walks the AST of a model and its imports once per concern, collecting
every error it finds (one run reports all of them), and on success returns
the :class:`~easylab.frontend.model.CheckedModel`. The rules are those of
docs/language.md; each error names the rule it enforces. The rules live in
one module per part of the language, composed here.
"""

from __future__ import annotations

from ...core.source import Diagnostics
from .. import ast
from ..model import CheckedModel
from .base import C_RESERVED, CheckerBase, kind_name
from .charts import ChartRules
from .data import DataRules
from .dataflows import DataflowRules
from .devices import DeviceRules
from .nodes import NodeRules
from .tasks import TaskRules

__all__ = ["C_RESERVED", "Checker", "check", "kind_name"]


class Checker(DataRules, DataflowRules, DeviceRules, ChartRules, TaskRules, NodeRules, CheckerBase):
    """Checks one loaded model; see :func:`check`."""


def check(modules: list[ast.Module], root: ast.Module, diags: Diagnostics) -> CheckedModel | None:
    """Check a loaded model; errors go to ``diags``, the model comes back if none."""
    return Checker(modules, root, diags).run()
