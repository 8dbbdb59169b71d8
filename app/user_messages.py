"""What the window tells the user when something fails: one mapping from exceptions to plain language (Qt-free).

Every error dialog and status message of the explorer goes through
:func:`user_message`. It never shows a Python class name (``BadZipFile``,
``KeyError``), a traceback or advice meant for programmers (numpy's ``allow_pickle``
hint): a file cut short says it is incomplete, a file of stored Python objects says
it is not a Lipspace file, an unexpected internal failure says so and what to try.
Messages the engine writes for the user (a file and what was expected in it) are
kept, with any technical parenthesis removed.

A task run in a worker thread raises :class:`UserError` (via :func:`plain_errors`) so
that the worker passes its message on unchanged.
"""
from __future__ import annotations

import re
import zipfile
from pathlib import Path

__all__ = ["UserError", "user_message", "plain_errors", "looks_technical"]


class UserError(Exception):
    """An error whose message is written for the user and is shown as it is."""


#: class-like words that must never reach a dialog
_TECHNICAL = re.compile(
    r"\b(?:[A-Z][A-Za-z]*(?:Error|Exception|Warning)|BadZipFile|Traceback|allow_pickle|pickle[ds]?|"
    r"NoneType|numpy|ndarray|dtype|KeyError|errno|__\w+__)\b")
#: a parenthesis or clause naming an exception class: "(BadZipFile: File is not a zip file)"
_CLASS_PAREN = re.compile(r"\s*\((?:[A-Za-z_.]*(?:Error|Exception|Warning|BadZipFile))(?::[^()]*)?\)")
_CLASS_PREFIX = re.compile(r"^(?:[A-Za-z_.]*(?:Error|Exception|Warning|BadZipFile)):\s*")
_DAMAGED = ("badzipfile", "not a zip file", "eoferror", "bad magic number", "bad crc-32")


#: "<path>: ..." or "<path>, line 3: ...": the file an engine message starts with
_LEADING_FILE = re.compile(r"^(\S+?\.[A-Za-z0-9]{1,8})(?:,[^:]*)?: ")


def _name(exc, path) -> str:
    p = path if path is not None else getattr(exc, "filename", None)
    if not p:
        m = _LEADING_FILE.match(str(exc))
        p = m.group(1) if m else None
    return Path(p).name if p else "the file"


def _sentence(text: str) -> str:
    return text[0].upper() + text[1:] if text.startswith("the file") else text


def looks_technical(text: str) -> bool:
    """Whether ``text`` names a Python class, a traceback or programmer advice."""
    return bool(_TECHNICAL.search(text))


def _clean(text: str) -> str:
    text = _CLASS_PREFIX.sub("", text.strip())
    text = _CLASS_PAREN.sub("", text)
    return re.sub(r"\s{2,}", " ", text).strip()


def user_message(exc: BaseException, *, doing: str = "open the file", path=None) -> str:
    """One plain-language sentence or two for ``exc`` (see :func:`_user_message`)."""
    return _sentence(_user_message(exc, doing=doing, path=path))


def _user_message(exc: BaseException, *, doing: str = "open the file", path=None) -> str:
    """One plain-language sentence or two for ``exc``, for a dialog or the status bar.

    Parameters
    ----------
    exc : BaseException
        What was raised.
    doing : str
        What the user asked for, completing "Lipspace could not ..." (``"open the file"``,
        ``"synthesise the trajectory"``).
    path : str or Path, optional
        The file concerned, when the exception does not name it.

    Returns
    -------
    str
        Never names a Python class or shows a traceback.
    """
    from engine.progress import Cancelled

    name = _name(exc, path)
    text = str(exc)
    low = f"{type(exc).__name__} {text}".lower()
    if isinstance(exc, UserError):
        return text
    if isinstance(exc, Cancelled):
        return "Cancelled: nothing was changed."
    if isinstance(exc, MemoryError):  # the one out-of-memory text: the size asked for and what lowers it
        from app.out_of_memory import memory_message

        return memory_message(exc, doing=doing)
    if isinstance(exc, FileNotFoundError):
        return f"{name}: there is no such file. It may have been moved, renamed or deleted."
    if isinstance(exc, IsADirectoryError):
        return f"{name} is a folder. Choose a file inside it."
    if isinstance(exc, PermissionError):
        return f"{name}: you are not allowed to read or write this file. Check its permissions."
    if isinstance(exc, (zipfile.BadZipFile, EOFError)) or any(w in low for w in _DAMAGED):
        return (f"{name} is damaged or incomplete: it was probably cut short while being written, copied or "
                "downloaded. Copy it again, or rebuild it with 'lipspace build'.")
    if "pickle" in low or "python objects" in low:
        return (f"{name} is not a file Lipspace wrote: it holds stored program objects, which Lipspace does not "
                "open for safety. Open a manifold from 'lipspace build', a corpus, or a recording.")
    if isinstance(exc, ValueError):  # the engine's data errors: file, place and what was expected
        plain = _clean(text)
        if plain and not looks_technical(plain):
            return plain
    elif isinstance(exc, OSError) and exc.strerror:
        return f"Lipspace could not {doing}: {name}: {exc.strerror.lower()}."
    if name == "the file":  # no file concerned: an internal problem
        return (f"Lipspace could not {doing}: something unexpected went wrong inside Lipspace. Try again; if "
                "it happens again, save the session (File › Save session) and report what you did.")
    return (f"Lipspace could not {doing}: {name} does not hold what Lipspace expected, or Lipspace met an "
            "internal problem. Check that it is a manifold from 'lipspace build', a corpus, or a recording "
            "Lipspace imports, and try again.")


def plain_errors(task, *, doing: str = "open the file", path=None):
    """``task`` (a worker task ``task(progress)``) whose failures are :class:`UserError` with :func:`user_message`.

    Cancellation passes through unchanged.
    """
    from engine.progress import Cancelled

    def wrapped(progress):
        try:
            return task(progress)
        except (Cancelled, UserError):
            raise
        except Exception as exc:  # noqa: BLE001 - every failure becomes one plain message
            raise UserError(user_message(exc, doing=doing, path=path)) from exc

    return wrapped
