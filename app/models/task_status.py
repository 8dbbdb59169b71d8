"""The text of a background task's progress in the status bar (Qt-free)."""
from __future__ import annotations

__all__ = ["stage_text"]


def stage_text(stage: str, done: int, total: int, seconds: float) -> str:
    """The label for one progress report: ``"embedding 3/10 · 4 s"``, or without a count."""
    count = f" {done}/{total}" if total > 1 and done < total else ""
    return f"{stage}{count} · {seconds:.0f} s"
