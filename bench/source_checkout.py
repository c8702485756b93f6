"""A benchmark run as a script from a source checkout, without the package
installed: `easylab` (generator/ plus host_tools/) made importable."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def make_easylab_importable() -> None:
    """Import `easylab` from the checkout unless it is installed."""
    try:
        import easylab.host_tools  # noqa: F401
    except ImportError:  # pragma: no cover - depends on the environment
        spec = importlib.util.spec_from_file_location(
            "easylab", ROOT / "generator" / "__init__.py",
            submodule_search_locations=[str(ROOT / "generator"), str(ROOT)])
        module = importlib.util.module_from_spec(spec)
        sys.modules["easylab"] = module
        spec.loader.exec_module(module)
