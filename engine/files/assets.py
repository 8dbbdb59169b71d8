"""Locating the files the program ships: the repository's ``assets/`` folder, installed as ``engine.assets``.

``assets/`` stays a top-level folder of the repository; ``pyproject.toml`` maps it onto the
package ``engine.assets`` (``[tool.setuptools.package-dir]``), so the wheel, the sdist and an
editable install all carry it as package data, read through :mod:`importlib.resources`.
A checkout run without installing anything (only ``PYTHONPATH`` pointing at it) has no
``engine.assets`` package: there the folder beside the ``engine`` package is read, the
same files.
"""
from __future__ import annotations

import functools
from importlib import resources
from pathlib import Path

__all__ = ["ASSETS_PACKAGE", "assets_dir", "asset_path"]

#: the package the repository's ``assets/`` folder is installed as
ASSETS_PACKAGE = "engine.assets"


@functools.lru_cache(maxsize=1)
def assets_dir() -> Path:
    """The folder holding the shipped files: ``engine.assets``'s, or a bare checkout's ``assets/``."""
    try:
        root = resources.files(ASSETS_PACKAGE)
    except ModuleNotFoundError:  # a checkout on PYTHONPATH, never installed: assets/ beside engine/
        return Path(__file__).resolve().parents[2] / "assets"
    # pip installs a wheel unpacked, so the package's files are files on disk (never inside a zip)
    return Path(str(root))


def asset_path(name: str) -> Path:
    """Path of the shipped asset ``name`` (e.g. ``"wordlist.txt"``).

    Raises
    ------
    FileNotFoundError
        If the file is missing, naming the folder searched and what it holds.
    """
    folder = assets_dir()
    path = folder / name
    if not path.is_file():
        known = sorted(p.name for p in folder.iterdir() if not p.name.startswith(("_", "."))) \
            if folder.is_dir() else []
        raise FileNotFoundError(
            f"asset {name!r} not found in {folder} (present: {', '.join(known) or 'none'}); "
            "the installation is incomplete: reinstall Lipspace (pip install lipspace, or pip install -e . in a "
            "checkout)"
        )
    return path
