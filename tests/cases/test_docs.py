"""docs/api.md is up to date with the docstrings (the tutorials run in tests/cases/test_tutorials.py)."""

from __future__ import annotations

import importlib.util
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _build_api():
    """docs/build_api.py as a module (registered in sys.modules: its dataclasses look their module up)."""
    if "build_api" not in sys.modules:
        spec = importlib.util.spec_from_file_location("build_api", ROOT / "docs" / "build_api.py")
        module = importlib.util.module_from_spec(spec)
        sys.modules["build_api"] = module
        spec.loader.exec_module(module)
    return sys.modules["build_api"]


def test_api_reference_is_up_to_date():
    build_api = _build_api()
    expected = build_api.build()
    current = (ROOT / "docs" / "api.md").read_text(encoding="utf-8")
    assert current == expected, "docs/api.md is out of date with the docstrings: run `python docs/build_api.py`"
