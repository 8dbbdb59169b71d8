"""Names of a package loaded from their modules on first use (PEP 562 ``__getattr__``)."""
from __future__ import annotations

import importlib

__all__ = ["lazy_names"]


def lazy_names(package: str, where: dict, namespace: dict):
    """``(__getattr__, __dir__)`` for ``package`` whose public names live in ``where`` (name -> module);
    a name, once loaded, is kept in ``namespace`` (the package's globals)."""

    def __getattr__(name):
        if name in where:
            value = getattr(importlib.import_module(where[name]), name)
            namespace[name] = value
            return value
        raise AttributeError(f"module {package!r} has no attribute {name!r}")

    def __dir__():
        return sorted(set(namespace) | set(where))

    return __getattr__, __dir__
