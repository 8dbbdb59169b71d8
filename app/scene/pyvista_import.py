"""pyvista's plotting package imported without matplotlib's figure machinery.

pyvista's plotting package imports ``matplotlib.pyplot`` (in its colour module) and the Agg
canvas (in its charts module) when it is imported, though it uses them only inside functions
Lipspace never calls on screen (matplotlib charts inside a 3-D scene, the matplotlib theme's
colour cycle). With them comes matplotlib's whole figure package: about half a second of the
window's start, all of it on the thread that has to draw the first frame.

:func:`import_plotting` imports pyvista's plotting package with a stand-in for each of those two
modules in ``sys.modules``. A stand-in resolves on first use: reading any attribute of it
imports the real module and returns the real attribute, so pyvista's functions that use them
work as before, only later. The stand-ins are taken out of ``sys.modules`` as soon as the
package is imported, so any other ``import matplotlib.pyplot`` (Lipspace's figures) gets the
real module. While the package is being imported, the one name pyvista takes from the Agg module
by ``from ... import`` (``FigureCanvasAgg``, which it only calls) is handed out as a function that
imports and calls the real class; any other name read then ends the deferral (both stand-ins are
taken out, the module read is imported there and then), so a pyvista that needs more at import
time is slower, not broken. Only the importing thread is handed such a function: another thread
that meets a stand-in meanwhile ends the deferral the same way and gets the real module's
attribute. Call :func:`import_plotting` before other threads draw with matplotlib.
"""
from __future__ import annotations

import importlib
import sys
import threading
import types

__all__ = ["import_plotting"]

# module -> the names pyvista's plotting package takes from it with ``from module import name``
# while it is imported (each only called, inside functions)
DEFERRED = {"matplotlib.pyplot": (), "matplotlib.backends.backend_agg": ("FigureCanvasAgg",)}

_lock = threading.Lock()  # one import of pyvista's plotting package at a time
_release_lock = threading.Lock()
_importing = {"thread": None}  # the thread importing pyvista's plotting package with stand-ins


class _DeferredModule(types.ModuleType):
    """Stands for the module of the same name until an attribute of it is read."""

    def __getattr__(self, attr: str):
        if attr.startswith("__") and attr.endswith("__"):  # the import system's questions
            raise AttributeError(attr)
        if sys.modules.get(self.__name__) is self:  # pyvista's plotting package is being imported
            if attr in DEFERRED[self.__name__] and _importing["thread"] == threading.get_ident():
                return _deferred_callable(self.__name__, attr)
            _release()
        return getattr(importlib.import_module(self.__name__), attr)


def _deferred_callable(module: str, name: str):
    """A function that imports ``module`` and calls its ``name`` with the arguments it is given."""
    def call(*args, **kwargs):
        return getattr(importlib.import_module(module), name)(*args, **kwargs)
    call.__name__ = call.__qualname__ = name
    call.__doc__ = f"{module}.{name}, imported when first called."
    return call


def _release() -> None:
    """Take the stand-ins out of ``sys.modules`` (the real modules are imported when next asked for)."""
    with _release_lock:
        for name in DEFERRED:
            if isinstance(sys.modules.get(name), _DeferredModule):
                del sys.modules[name]


def import_plotting() -> types.ModuleType:
    """Import ``pyvista.plotting`` (once) with matplotlib's pyplot and Agg canvas put off.

    Nothing is put off when pyvista's plotting package or one of the two modules is imported
    already. Returns the plotting package.
    """
    if "pyvista.plotting" in sys.modules:  # (import_module waits for an import still running)
        return importlib.import_module("pyvista.plotting")
    with _lock:
        if "pyvista.plotting" in sys.modules or any(name in sys.modules for name in DEFERRED):
            return importlib.import_module("pyvista.plotting")
        import matplotlib  # noqa: F401  (the parent package, imported by pyvista anyway)

        with _release_lock:
            for name in DEFERRED:
                sys.modules[name] = _DeferredModule(name)
        _importing["thread"] = threading.get_ident()
        try:
            return importlib.import_module("pyvista.plotting")
        finally:
            _importing["thread"] = None
            _release()
