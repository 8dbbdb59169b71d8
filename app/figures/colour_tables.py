"""The colour tables the explorer's Qt-free colouring reads, written from matplotlib's colormaps.

:mod:`app.models.colouring` must not import matplotlib (it runs in the window and in the
Qt-free state); it reads ``app/models/colour_tables.json``, which
:func:`write_colour_tables` makes and ``tests/app/models/test_colouring.py`` checks against
matplotlib entry by entry.
"""
from __future__ import annotations

import json
from pathlib import Path

from engine.files.atomic import atomic_write

__all__ = ["TABLES", "colour_tables", "write_colour_tables", "TABLE_FILE"]

#: continuous maps (256 entries each) and listed palettes the explorer uses
TABLES = ("jet", "YlOrRd_r", "PuBu_r", "tab20", "tab20b", "tab20c")
TABLE_FILE = Path(__file__).resolve().parents[1] / "models" / "colour_tables.json"


def colour_tables() -> dict:
    """``{name: [[r, g, b], ...]}`` of :data:`TABLES` from matplotlib (its lookup-table entries)."""
    import numpy as np
    from matplotlib import colormaps

    out = {}
    for name in TABLES:
        cm = colormaps[name]
        rgb = np.asarray(cm.colors)[:, :3] if hasattr(cm, "colors") and name.startswith("tab") \
            else cm(np.arange(cm.N))[:, :3]
        out[name] = [[round(float(v), 8) for v in row] for row in rgb]
    return out


def write_colour_tables(path=TABLE_FILE) -> Path:
    """Write :func:`colour_tables` as JSON to ``path`` (atomically)."""
    path = Path(path)
    with atomic_write(path) as tmp:
        Path(tmp).write_text(json.dumps(colour_tables(), separators=(",", ":")) + "\n")
    return path


if __name__ == "__main__":
    print(f"wrote {write_colour_tables()}")
