"""File › Export frame table and File › Export TextGrids: the window's faces of ``lipspace table`` (Qt-free).

The same table (:func:`engine.manifold.frame_table.frame_table`, units in a JSON sidecar) and
the same TextGrids (:func:`engine.manifold.frame_table.write_textgrids`) as the command line
writes, so a table exported from the window and one from ``lipspace table`` are equal.
"""
from __future__ import annotations

from pathlib import Path

__all__ = ["export_frame_table", "export_textgrids", "existing_textgrids", "table_filters"]


def table_filters() -> str:
    """The save dialog's filters: CSV, and Parquet where pyarrow is installed."""
    from engine.io.writers.tidy import have_parquet

    return "CSV table (*.csv)" + (";;Parquet table (*.parquet)" if have_parquet() else "")


def export_frame_table(manifold, path, *, source: str = "", progress=None) -> list[Path]:
    """Write the per-frame table to ``path`` (.csv or .parquet) and its sidecar; returns both paths."""
    from engine.io.writers.tidy import write_frame_table
    from engine.manifold.frame_table import frame_table
    from engine.progress import report

    report(progress, "frame table", 0, 1)
    table = frame_table(manifold, source=source)
    out = write_frame_table(path, table)
    report(progress, "frame table", 1, 1)
    return out


def existing_textgrids(manifold, directory) -> list[Path]:
    """The TextGrids :func:`export_textgrids` would replace in ``directory``."""
    from engine.io.writers.praat import textgrid_names

    d = Path(directory)
    return [d / n for n in textgrid_names(u.id for u in manifold.corpus_.utterances) if (d / n).exists()]


def export_textgrids(manifold, directory, *, source: str = "", progress=None) -> list[Path]:
    """One TextGrid per utterance into ``directory``; returns the files written."""
    from engine.manifold.frame_table import frame_table, write_textgrids

    return write_textgrids(manifold, frame_table(manifold, n_fx=0, source=source), directory, progress=progress)
