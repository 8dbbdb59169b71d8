"""Progress reporting and cancellation shared by every long engine step.

A long step takes ``progress=`` (a callable ``progress(stage, done, total)``) and
calls it as it goes. To cancel, the callable raises :class:`Cancelled` (the GUI's
worker does this when the user presses Cancel; the command line turns Ctrl-C into
it). Engine objects are left unfitted when a fit is cancelled.
"""
from __future__ import annotations

from collections.abc import Callable

__all__ = ["Cancelled", "ProgressFn", "report"]

ProgressFn = Callable[[str, int, int], None] | None


class Cancelled(Exception):
    """Raised from a progress callback to stop long work cleanly."""


def report(progress: ProgressFn, stage: str, done: int, total: int) -> None:
    """Call ``progress`` if given."""
    if progress is not None:
        progress(stage, int(done), int(total))
