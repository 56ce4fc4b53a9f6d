"""Lazy package exports (PEP 562): a package names what it offers and imports a submodule
only when one of its names is used, so importing a numpy-only piece never pulls in gmsh,
dolfinx, PETSc or numba."""
from __future__ import annotations

import importlib


def lazy_exports(package: str, exports: dict[str, str]):
    """``__getattr__, __dir__`` for a package whose name -> submodule map is ``exports``
    (e.g. ``{"StackLayout": ".layout"}``)."""

    def __getattr__(name: str):
        if name in exports:
            return getattr(importlib.import_module(exports[name], package), name)
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(exports)

    return __getattr__, __dir__
