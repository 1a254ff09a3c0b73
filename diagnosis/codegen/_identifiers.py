"""Names made C and Python identifiers (module, ARR and signal names), and the check that no two collide."""

from __future__ import annotations

import re

from ._errors import CodegenError

__all__ = ["identifier", "unique"]


def identifier(text: str, what: str) -> str:
    """``text`` mapped to a C and Python identifier: other characters become ``_``, a leading digit gets ``_``."""
    if not isinstance(text, str) or not text:
        raise CodegenError(f"{what}: a non-empty name is needed, got {text!r}")
    ident = re.sub(r"[^A-Za-z0-9_]", "_", text)
    return "_" + ident if ident[0].isdigit() else ident


def unique(pairs: list[tuple[str, str]], what: str) -> None:
    seen: dict = {}
    for ident, original in pairs:
        if ident in seen and seen[ident] != original:
            raise CodegenError(f"{what}: {seen[ident]!r} and {original!r} both become the identifier {ident!r}; "
                               "rename one")
        seen[ident] = original

