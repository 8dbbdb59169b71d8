"""Names kept at an old home after a rename or a move: loaded from the new one on use, with a warning.

A module lists its old names, ``{old name: (new module, new name)}``, and takes the
``__getattr__`` :func:`deprecated_names` gives (PEP 562). Only names a user's script or a saved
file could hold are kept; the engine and the app use the new names.
"""
from __future__ import annotations

import importlib
import warnings
from collections.abc import Callable
from typing import Any

__all__ = ["deprecated_names"]


def deprecated_names(module: str, moved: dict[str, tuple[str, str]]) -> Callable[[str], Any]:
    """A module ``__getattr__`` giving each of ``moved``'s old names from its new home, warning on use.

    Parameters
    ----------
    module : str
        The old module's dotted name (for the messages).
    moved : dict of str to (str, str)
        Old name -> (the module it now lives in, its name there).

    Returns
    -------
    callable
        ``__getattr__(name)``: the object, after a :class:`DeprecationWarning` naming the new
        import; AttributeError for other names.
    """

    def __getattr__(name: str) -> Any:
        if name not in moved:
            raise AttributeError(f"module {module!r} has no attribute {name!r}")
        where, new = moved[name]
        warnings.warn(f"{module}.{name} is deprecated: use {where}.{new} (from {where} import {new})",
                      DeprecationWarning, stacklevel=2)
        return getattr(importlib.import_module(where), new)

    return __getattr__
