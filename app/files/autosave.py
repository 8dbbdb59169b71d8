"""Autosave: the explorer's session is kept on disk while it changes, and offered back after a crash.

Qt-free logic; the window only calls :meth:`Autosaver.tick` from a timer.

* **Where**: the user's state directory (``platformdirs.user_state_dir("lipspace")``,
  or ``$LIPSPACE_STATE_DIR``), subfolder ``autosave/``.
* **What**: a normal session file (:mod:`app.files.session`: selection, modes, cameras, the
  editor's settings and edited key targets, the synthesised trajectory), one per
  running explorer process: ``autosave-<run>.lipspace.json`` (+ ``.npz``), written
  atomically; ``<run>`` is the process id and its start time in milliseconds (pids are
  reused, e.g. after a reboot).
* **When**: debounced. Each tick the window hands a cheap fingerprint of the session
  (:func:`session_fingerprint`); a save happens once the fingerprint has stayed the same
  for ``delay`` seconds after it last changed (3 s by default), so dragging a camera or
  clicking through states writes once when the user pauses, never on every event; a
  session that keeps changing is still saved ``max_delay`` seconds (30 s) after its
  first unsaved change.
* **Abnormal exit**: each process writes a marker ``running-<run>.json`` at start
  (:meth:`Autosaver.begin`) and removes it, with its autosave, at a clean exit
  (:meth:`Autosaver.finish`). A marker whose process is gone means that run ended
  abnormally (crash, kill, power loss); if it left an autosave, :meth:`begin` returns
  it as a :class:`Recovery` and :func:`resolve_recovery` decides (from ``--restore`` /
  ``--no-restore`` or by asking) whether to reopen it.
"""
from __future__ import annotations

import contextlib
import json
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from engine.files.atomic import write_text_atomic

__all__ = ["STATE_DIR_ENV", "DEFAULT_DELAY_S", "DEFAULT_MAX_DELAY_S", "state_dir", "Recovery", "Autosaver",
           "session_fingerprint", "resolve_recovery", "pid_alive"]

STATE_DIR_ENV = "LIPSPACE_STATE_DIR"
DEFAULT_DELAY_S = 3.0
DEFAULT_MAX_DELAY_S = 30.0
_MARKER = "running-{run}.json"
#: the largest marker read (one is under 100 bytes)
MAX_MARKER_BYTES = 64 * 1024
_SESSION = "autosave-{run}.lipspace.json"


def state_dir() -> Path:
    """Lipspace's state directory (``$LIPSPACE_STATE_DIR`` or the platform user state dir)."""
    from engine.files.userdirs import user_dir

    return user_dir("state", STATE_DIR_ENV)


def _start_ticks(pid: int) -> int | None:
    """The process's start time in clock ticks since boot (Linux), to tell a reused pid apart."""
    try:
        with open(f"/proc/{pid}/stat", encoding="ascii", errors="replace") as fh:
            return int(fh.read().rsplit(")", 1)[1].split()[19])
    except (OSError, IndexError, ValueError):
        return None


def _started_at(pid: int) -> float | None:
    """When process ``pid`` started, in seconds since the epoch (Linux), else None."""
    ticks = _start_ticks(pid)
    if ticks is None:
        return None
    try:
        with open("/proc/stat", encoding="ascii") as fh:
            boot = next(int(line.split()[1]) for line in fh if line.startswith("btime "))
        return boot + ticks / os.sysconf("SC_CLK_TCK")
    except (OSError, StopIteration, ValueError, IndexError):
        return None


#: a run writes its marker this soon after its process started (Python, Qt and the window's imports)
MARKER_WITHIN_S = 120.0


def _mtime(p: Path) -> float | None:
    try:
        return p.stat().st_mtime
    except OSError:
        return None


def pid_alive(pid: int, start_ticks: int | None = None, started: float | None = None) -> bool:
    """Whether process ``pid`` runs and is the one a marker names: the one that started at
    ``start_ticks`` when the marker says; else, when the marker says when its run ``started``
    (seconds since the epoch), one that started at most :data:`MARKER_WITHIN_S` before that
    (pid 1, started at boot, is not a crashed explorer that wrote its marker an hour later)."""
    if pid <= 0:
        return False
    if sys.platform.startswith("win"):
        import ctypes

        kernel32 = ctypes.windll.kernel32
        handle = kernel32.OpenProcess(0x1000, False, pid)  # PROCESS_QUERY_LIMITED_INFORMATION
        if not handle:
            return False
        code = ctypes.c_ulong()
        ok = kernel32.GetExitCodeProcess(handle, ctypes.byref(code))
        kernel32.CloseHandle(handle)
        return bool(ok) and code.value == 259  # STILL_ACTIVE
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:
        pass  # someone else's process: it exists
    if start_ticks is not None:
        now = _start_ticks(pid)
        if now is not None and now != start_ticks:
            return False  # the pid was reused by another process
    elif started is not None:
        at = _started_at(pid)
        if at is not None and not started - MARKER_WITHIN_S <= at <= started + 5.0:
            return False  # a process that started long before (or after) the run that wrote the marker
    return True


@dataclass(frozen=True)
class Recovery:
    """An autosave left by a run that did not exit cleanly.

    Attributes
    ----------
    session : Path
        Its session file (open with :func:`app.files.session.load_session`).
    marker : Path
        The dead run's marker.
    pid : int
        The dead run's process id.
    started, saved : float
        When that run started and when the autosave was written (seconds since the epoch).
    """

    session: Path
    marker: Path
    pid: int
    started: float
    saved: float

    def describe(self) -> str:
        """One sentence for the restore question."""
        when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(self.saved))
        return (f"Lipspace did not exit normally last time (process {self.pid}). Its session was autosaved at "
                f"{when}: selection, camera, targets and synthesised trajectory.")


def session_fingerprint(state, *, cameras: dict | None = None, extra: dict | None = None, targets=None):
    """A cheap value that changes whenever the saved session would (None: nothing to save yet).

    The JSON part of the session plus the identity of the synthesised trajectory and
    of the targets (both are replaced, never changed in place, when they change).
    """
    from app.files.session import session_dict

    if state.manifold is None:
        return None
    d = session_dict(state, cameras=cameras, extra=extra, targets=targets)
    return json.dumps(d, sort_keys=True, default=str), id(state.synthetic), id(targets)


class Autosaver:
    """Debounced autosave of one explorer process, and crash detection.

    Parameters
    ----------
    directory : path, optional
        Where markers and autosaves go (default ``state_dir() / "autosave"``).
    delay : float, default=3.0
        Seconds the session must stay unchanged after a change before it is saved.
    max_delay : float, default=30.0
        Seconds after the first unsaved change when it is saved even if it keeps changing.
    clock : callable() -> float, default=time.monotonic
    pid : int, optional
        This process's id (default ``os.getpid()``; tests simulate other runs).
    """

    def __init__(self, directory=None, *, delay: float = DEFAULT_DELAY_S, max_delay: float = DEFAULT_MAX_DELAY_S,
                 clock=time.monotonic, pid: int | None = None):
        if not delay >= 0:
            raise ValueError(f"autosave delay must be >= 0 seconds, got {delay!r}")
        if not max_delay >= delay:
            raise ValueError(f"autosave max_delay must be >= delay ({delay} s), got {max_delay!r}")
        self.max_delay = float(max_delay)
        self.directory = Path(directory) if directory is not None else state_dir() / "autosave"
        self.delay = float(delay)
        self.clock = clock
        self.pid = os.getpid() if pid is None else int(pid)
        self.run = f"{self.pid}-{time.time_ns() // 1_000_000}"
        self.marker = self.directory / _MARKER.format(run=self.run)
        self.session = self.directory / _SESSION.format(run=self.run)
        self._fingerprint = None
        self._changed_at = self._dirty_since = None
        self.dirty = False
        self.saves = 0
        self.last_error: str | None = None
        self._inherited: Recovery | None = None
        #: damaged files of earlier runs moved to ``damaged/`` by :meth:`begin`, one sentence each
        self.set_aside: list[str] = []

    # ------------------------------------------------------------------ run markers
    def begin(self) -> Recovery | None:
        """Write this run's marker; return the newest autosave of a run that ended abnormally.

        Stale markers of dead runs that left no autosave are removed. Raises OSError
        when the directory cannot be written (the caller runs without autosave then).
        """
        self.directory.mkdir(parents=True, exist_ok=True)
        self._clear_dead_temporaries()
        found = []
        for marker in self.directory.glob(_MARKER.format(run="*")):
            if marker == self.marker:
                continue
            info, why = self._read_marker(marker)
            if why is not None:  # set aside, said, and the window opens as if it were not there
                self.set_aside.append(self.move_aside(marker, why))
                continue
            pid = info.get("pid")
            started = info.get("started") or _mtime(marker)  # a marker without it: when it was written
            if isinstance(pid, int) and pid != self.pid and pid_alive(pid, info.get("start_ticks"), started):
                continue  # another explorer that is still running
            session = self.directory / _SESSION.format(run=marker.stem[len("running-"):])
            if isinstance(pid, int) and session.is_file():
                found.append(Recovery(session, marker, pid, float(info.get("started", 0.0)),
                                      session.stat().st_mtime))
            else:
                marker.unlink(missing_ok=True)  # died before its first autosave: nothing to offer
        write_text_atomic(self.marker, json.dumps({"pid": self.pid, "started": time.time(),
                                                   "start_ticks": _start_ticks(self.pid)}) + "\n")
        return max(found, key=lambda r: r.saved, default=None)

    def _clear_dead_temporaries(self) -> None:
        """Remove the temporary files of autosaves and markers whose writing process was killed
        (each run's names differ, so no later save of the same name would find them)."""
        from engine.files.placing import process_gone

        for p in self.directory.glob(".*"):
            if not p.name.lstrip(".").startswith(("autosave-", "running-")) or ".p" not in p.name:
                continue
            with contextlib.suppress(OSError):
                if p.is_file() and not p.is_symlink() and process_gone(p.name, p.stat().st_mtime):
                    p.unlink()

    @staticmethod
    def _read_marker(path: Path) -> tuple[dict | None, str | None]:
        """(the marker's fields, None) or (None, what is wrong with it)."""
        import math

        from engine.files.bounded import parse_json, read_bounded

        try:  # a regular file of a few bytes: never a FIFO, a device or a huge file
            d = parse_json(read_bounded(path, limit=MAX_MARKER_BYTES, what="autosave marker"), source=path)
        except FileNotFoundError:  # another explorer finished meanwhile
            return {}, None
        except (OSError, ValueError) as exc:
            return None, f"not readable JSON ({str(exc).removeprefix(f'{path}: ')})"
        if not isinstance(d, dict):
            return None, "not a JSON object"
        pid, started, ticks = d.get("pid"), d.get("started", 0.0), d.get("start_ticks")
        if not isinstance(pid, int) or isinstance(pid, bool) or pid <= 0:
            return None, f"'pid' is {json.dumps(pid)[:30]}, expected a process id"
        if isinstance(started, bool) or not isinstance(started, (int, float)) or not math.isfinite(started):
            return None, f"'started' is {json.dumps(started)[:30]}, expected a time in seconds"
        if ticks is not None and (not isinstance(ticks, int) or isinstance(ticks, bool)):
            return None, f"'start_ticks' is {json.dumps(ticks)[:30]}, expected a whole number or null"
        return d, None

    def move_aside(self, path: Path, why: str) -> str:
        """Move a damaged file of an earlier run to ``damaged/`` (kept for a look, never read again);
        returns the sentence that says so."""
        dest_dir = self.directory / "damaged"
        dest = dest_dir / f"{path.name}.{time.strftime('%Y%m%d-%H%M%S')}"
        try:
            dest_dir.mkdir(parents=True, exist_ok=True)
            os.replace(path, dest)
        except OSError as exc:
            with contextlib.suppress(OSError):
                path.unlink()
            return f"{path} is damaged ({why}) and could not be moved aside ({exc.strerror or exc}); it was removed"
        return f"{path} is damaged ({why}); it was moved to {dest}"

    def discard(self, recovery: Recovery) -> None:
        """Delete a dead run's marker and autosave (after it was restored or declined)."""
        from app.files.session import arrays_path

        for p in (recovery.session, arrays_path(recovery.session), recovery.marker):
            p.unlink(missing_ok=True)

    def adopt(self, recovery: Recovery) -> None:
        """Keep a restored autosave on disk until this run's first autosave replaces it.

        Should this run die before saving, the next start offers the same autosave again.
        """
        self._inherited = recovery

    def finish(self) -> None:
        """Clean exit: remove this run's marker and autosave (there is nothing to recover)."""
        from app.files.session import arrays_path

        if self._inherited is not None:
            self.discard(self._inherited)
            self._inherited = None
        for p in (self.session, arrays_path(self.session), self.marker):
            p.unlink(missing_ok=True)

    # ------------------------------------------------------------------ debounced saving
    def observe(self, fingerprint, now: float | None = None) -> None:
        """Note the session's current fingerprint; a different one starts the delay again."""
        if fingerprint is None or fingerprint == self._fingerprint:
            return
        self._fingerprint = fingerprint
        self._changed_at = self.clock() if now is None else now
        if not self.dirty:
            self._dirty_since = self._changed_at
        self.dirty = True

    def due(self, now: float | None = None) -> bool:
        """Whether the session changed and then stayed unchanged for ``delay`` seconds (or has
        been changing for ``max_delay`` seconds)."""
        now = self.clock() if now is None else now
        return self.dirty and (now - self._changed_at >= self.delay or now - self._dirty_since >= self.max_delay)

    def save(self, write) -> Path:
        """Write the autosave now with ``write(path)`` (e.g. :func:`app.files.session.save_session`)."""
        write(self.session)
        self.dirty = False
        self.saves += 1
        self.last_error = None
        if self._inherited is not None:  # the restored session lives on in ours now
            self.discard(self._inherited)
            self._inherited = None
        return self.session

    def tick(self, fingerprint, write, now: float | None = None) -> bool:
        """Observe ``fingerprint`` and save if due; returns whether it saved.

        A failed write (disk full, directory removed) is kept in :attr:`last_error` and
        retried at the next change; it never raises into the caller's timer.
        """
        self.observe(fingerprint, now)
        if not self.due(now):
            return False
        try:
            self.save(write)
        except (OSError, ValueError) as exc:
            self.dirty = False  # retry when the session changes again
            self.last_error = f"autosave to {self.session} failed: {exc}"
            return False
        return True


def resolve_recovery(autosaver: Autosaver, recovery: Recovery | None, *, restore: bool | None, ask=None):
    """Decide what to do with a dead run's autosave; returns the session dict to open, or None.

    Parameters
    ----------
    restore : bool or None
        ``True`` (``--restore``): reopen it without asking; ``False`` (``--no-restore``):
        leave it on disk (offered again next time) and start fresh; ``None``: ask.
    ask : callable(Recovery) -> {"restore", "discard", "later"}, optional
        The question (a dialog in the window); without it, ``None`` means "later".

    A discarded autosave is deleted; a restored one is kept until this run has
    autosaved (:meth:`Autosaver.adopt`). An autosave that cannot be read raises
    :class:`app.files.session.SessionError` after it is moved to ``damaged/`` (so it is not
    offered again, but kept for a look), with the reason and where it went.
    """
    from app.files.session import SessionError, load_session

    if recovery is None:
        return None
    if restore is None:
        answer = ask(recovery) if ask is not None else "later"
    else:
        answer = "restore" if restore else "later"
    if answer not in ("restore", "discard", "later"):
        raise ValueError(f"ask() must answer 'restore', 'discard' or 'later', got {answer!r}")
    if answer == "later":
        return None
    if answer == "discard":
        autosaver.discard(recovery)
        return None
    try:
        d = load_session(recovery.session)
    except SessionError as exc:
        from app.files.session import arrays_path

        moved = autosaver.move_aside(recovery.session, "it cannot be restored")
        for p in (arrays_path(recovery.session), recovery.marker):
            if p.exists():
                autosaver.move_aside(p, "its session cannot be restored")
        raise SessionError(f"the autosaved session could not be restored: {exc}. {moved}") from None
    autosaver.adopt(recovery)
    return d
