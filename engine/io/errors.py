"""The one error every importer raises for bad input (:class:`ImportFormatError`) and the
one warning for input read with a repair (:class:`ImportDataWarning`)."""
from __future__ import annotations

from engine.recordings.corpus import CorpusWarning

__all__ = ["ImportFormatError", "ImportDataWarning"]


class ImportFormatError(ValueError):
    """A foreign file does not hold what its format promises.

    The message names the file, the line (text formats) or frame / byte offset
    (binary formats) where reading stopped, what was found and what was expected.

    Parameters
    ----------
    path : str or path-like
        The file (or directory) being read.
    message : str
        What was found and what was expected; may suggest the fix.
    line : int, optional
        1-based line number in a text file.
    frame : int, optional
        0-based frame index in a track or sequence (a table that numbers its frames: its
        own number).

    Attributes
    ----------
    path, line, frame : as given
    detail : str
        ``message`` without the location prefix.
    """

    def __init__(self, path, message: str, *, line: int | None = None, frame: int | None = None):
        self.path = str(path)
        self.line = line
        self.frame = frame
        self.detail = message
        where = self.path
        if line is not None:
            where += f", line {line}"
        if frame is not None:
            where += f", frame {frame}"
        super().__init__(f"{where}: {message}")

    def __reduce__(self):  # keep picklable despite the keyword-only constructor
        return (_rebuild, (self.path, self.detail, self.line, self.frame))


def _rebuild(path, detail, line, frame):
    return ImportFormatError(path, detail, line=line, frame=frame)


class ImportDataWarning(CorpusWarning):
    """A file was read, but something in it was repaired or cut (dropped frames
    interpolated, an alignment longer than the data cut): the message says what."""
