"""The module reference page, written from the source tree at every build.

Sphinx reads ``generated/modules.rst``, which this extension writes when the configuration has
been read, before the sources are collected: one section per package of ``engine`` and ``app``,
each an autosummary table of the package and its modules, so the table shows every module with
the first sentence of its docstring and autosummary writes a page for each. The list is found
by walking the folders (``__init__.py`` marks a package), never kept by hand: a new module is in
the reference at the next build. ``tests/test_module_reference.py`` checks the walk against the
files and that every module has a docstring.
"""
from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

#: the packages whose modules make up the reference, in the order shown
PACKAGES = ("engine", "app")

#: the page written, relative to the docs folder, and where autosummary puts the module pages
PAGE = Path("generated") / "modules.rst"
TOCTREE = "modules"

INTRO = """\
Module reference
================

Every module of the two packages, one table per package, each with the first sentence of the
module's docstring; a module's page documents its public names. ``engine`` computes and never
imports Qt, VTK, pyvista or matplotlib; ``app`` is the window and the ``lipspace`` command line.
How the packages fit together is in the architecture page. This page is written from the source
tree at every build, so no module is left out.
"""


def package_modules(root: Path = ROOT, packages: tuple[str, ...] = PACKAGES) -> dict[str, list[str]]:
    """Every module of `packages` under `root`, grouped by the package that holds it.

    Parameters
    ----------
    root : Path
        The folder holding the packages (the repository).
    packages : tuple of str
        The top-level packages to walk.

    Returns
    -------
    dict of str to list of str
        Package name → its dotted module names, the package itself first, then its modules
        (``.py`` files) in name order. Packages come in the order of `packages`, each followed
        by its sub-packages in name order; a sub-package is a key of its own.
    """
    groups: dict[str, list[str]] = {}
    for top in packages:
        for init in sorted((root / top).rglob("__init__.py")):
            folder = init.parent
            if "__pycache__" in folder.parts:
                continue
            dotted = ".".join(folder.relative_to(root).parts)
            modules = [dotted]
            for source in sorted(folder.glob("*.py")):
                if source.name != "__init__.py":
                    modules.append(f"{dotted}.{source.stem}")
            groups[dotted] = modules
    return dict(sorted(groups.items(), key=lambda item: (packages.index(item[0].split(".")[0]), item[0])))


def page_text(groups: dict[str, list[str]]) -> str:
    """The reStructuredText of the module reference page.

    Parameters
    ----------
    groups : dict of str to list of str
        What `package_modules` returns.

    Returns
    -------
    str
        The page: the introduction, then per package a section with one autosummary table.
    """
    parts = [INTRO]
    for package, modules in groups.items():
        title = f"``{package}``"
        parts.append(f"\n{title}\n{'-' * len(title)}\n\n.. autosummary::\n   :toctree: {TOCTREE}\n\n")
        parts.extend(f"   {name}\n" for name in modules)
    return "".join(parts)


def write_page(srcdir: Path) -> Path:
    """Write the page into `srcdir` (only when its text changed, so a rebuild stays incremental).

    Parameters
    ----------
    srcdir : Path
        The docs folder.

    Returns
    -------
    Path
        The page written.
    """
    path = Path(srcdir) / PAGE
    text = page_text(package_modules())
    if not path.exists() or path.read_text(encoding="utf-8") != text:
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text, encoding="utf-8")
    return path


def _config_inited(app, config) -> None:
    write_page(Path(app.srcdir))


def setup(app):
    """Register the page writer with Sphinx (it runs before the sources are collected)."""
    app.connect("config-inited", _config_inited)
    return {"parallel_read_safe": True, "parallel_write_safe": True}
