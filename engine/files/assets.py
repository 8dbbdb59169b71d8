"""Locating the files the program ships in ``assets/``."""
from __future__ import annotations

from pathlib import Path

__all__ = ["ASSETS_DIR", "asset_path"]

#: The ``assets/`` folder beside the ``engine`` package.
ASSETS_DIR = Path(__file__).resolve().parents[2] / "assets"


def asset_path(name: str) -> Path:
    """Path of the shipped asset ``name`` (e.g. ``"wordlist.txt"``).

    Raises
    ------
    FileNotFoundError
        If the file is missing, naming the folder searched.
    """
    path = ASSETS_DIR / name
    if not path.is_file():
        known = sorted(p.name for p in ASSETS_DIR.iterdir()) if ASSETS_DIR.is_dir() else []
        raise FileNotFoundError(
            f"asset {name!r} not found in {ASSETS_DIR} (present: {', '.join(known) or 'none'}); "
            "the installation is incomplete: reinstall Lipspace or restore the assets/ folder"
        )
    return path
