"""A package's public names, each loaded from its module when first used (PEP 562).

The CAD kernel, the renderer, the statistics and optimisation libraries take seconds to
import; a package that re-exports its modules' names (``from cad import build_parts``)
should not make a command that uses one number from it wait for all of them.
"""

from __future__ import annotations

import importlib
import sys
from collections.abc import Callable
from typing import Any


def lazy_exports(
    package: str, where: dict[str, str]
) -> tuple[Callable[[str], Any], Callable[[], list[str]]]:
    """The ``__getattr__`` and ``__dir__`` of ``package``: each name of ``where`` (name ->
    the module defining it) is imported on first access and kept in the package."""

    def __getattr__(name: str) -> Any:
        if name not in where:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(where[name]), name)
        setattr(sys.modules[package], name, value)
        return value

    def __dir__() -> list[str]:
        return sorted(where)

    return __getattr__, __dir__
