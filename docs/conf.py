"""Sphinx configuration: the user guide, method and results pages (Markdown, through MyST) and the
API reference generated from the code's numpydoc docstrings (autosummary), with the module
reference listed from the source tree at every build (``_ext/module_reference.py``). ``make docs``
builds it with warnings as errors."""
from __future__ import annotations

import os
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(Path(__file__).resolve().parent / "_ext"))
os.environ.setdefault("QT_QPA_PLATFORM", "offscreen")  # the app's modules import Qt; nothing is shown

import engine  # noqa: E402

project = "Lipspace"
author = "The Lipspace developers"
copyright = "The Lipspace developers"  # noqa: A001
release = version = engine.__version__

extensions = [
    "sphinx.ext.autodoc",
    "sphinx.ext.autosummary",
    "sphinx.ext.mathjax",
    "numpydoc",
    "myst_parser",
    "module_reference",  # docs/_ext: writes generated/modules.rst, every module of engine and app
]
source_suffix = {".rst": "restructuredtext", ".md": "markdown"}
root_doc = "index"
exclude_patterns = ["_build", "screenshots/*.py", "gltf_web_check"]
templates_path = ["_templates"]

# API reference: one page per public name and per module, generated at build time
autosummary_generate = True
autosummary_imported_members = False
# a module documents the members it defines, not the names it re-exports (an old import path):
# those have their page where they are defined
autodoc_default_options = {"members": True, "show-inheritance": False, "ignore-module-all": True}
autodoc_typehints = "none"           # numpydoc's Parameters sections give the types
numpydoc_show_class_members = False  # autosummary lists members
numpydoc_class_members_toctree = False
numpydoc_xref_param_type = False

myst_heading_anchors = 3
myst_enable_extensions = ["colon_fence"]
suppress_warnings = ["myst.header"]  # the Markdown pages start at level 2 under their title in places

html_theme = "pydata_sphinx_theme"
html_title = f"Lipspace {release}"
html_theme_options = {"navigation_depth": 2, "show_toc_level": 2}
html_static_path: list[str] = []

#: what engine.estimator.Estimator gives every estimator (its API is scikit-learn's): documented there, not on each page
_INHERITED = {"get_params", "set_params", "get_metadata_routing"}


def _skip_estimator_plumbing(app, what, name, obj, skip, options):
    if name in _INHERITED or (name.startswith("set_") and name.endswith("_request")):
        return True
    home = getattr(obj, "__module__", None)
    if what == "module" and isinstance(obj, type) and not (isinstance(home, str) and home.split(".")[0] in ("engine",
                                                                                                              "app")):
        return True  # a library's class imported into a module (compiled ones hide where they come from)
    return None


def setup(app):
    app.connect("autodoc-skip-member", _skip_estimator_plumbing)
