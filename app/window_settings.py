"""What the window remembers between runs: its geometry, the dock layout and the recent files (QSettings).

Stored with :class:`QtCore.QSettings` in the user's configuration (INI format):
``$LIPSPACE_CONFIG_DIR/lipspace.ini`` when that variable is set (tests point it at a
temporary folder), else Qt's per-user location for organisation and application
"Lipspace". Keys:

``window/geometry``, ``window/state``
    :meth:`QMainWindow.saveGeometry` / :meth:`QMainWindow.saveState` (docks: where,
    how big, shown or hidden, tabbed), written when the window closes, restored when it
    opens. ``window/layout_version`` guards the state: a layout saved by a build with
    other docks is ignored rather than restored half.
``recent/files``
    Up to :data:`MAX_RECENT` paths of files opened, most recent first.
"""
from __future__ import annotations

import os
from pathlib import Path

from PySide6 import QtCore, QtWidgets

__all__ = ["CONFIG_DIR_ENV", "MAX_RECENT", "LAYOUT_VERSION", "dock_names", "open_settings", "WindowSettings"]

CONFIG_DIR_ENV = "LIPSPACE_CONFIG_DIR"
MAX_RECENT = 10
#: bump when the docks change, so that an old saved layout is not restored over new docks (a layout is
#: also kept only for the set of docks it was saved with: :func:`dock_names`)
LAYOUT_VERSION = 2


#: the largest settings file read (one is a few kB: two saved layouts and ten file names)
MAX_SETTINGS_BYTES = 4 * 2**20


def dock_names(window) -> str:
    """The object names of ``window``'s docks, sorted and joined: a saved layout is restored only over the
    same docks (a layout saved before a dock existed would leave the new one wherever Qt put it)."""
    return " ".join(sorted(d.objectName() for d in window.findChildren(QtWidgets.QDockWidget)))


def settings_file() -> Path:
    """Where the settings live: ``$LIPSPACE_CONFIG_DIR/lipspace.ini``, else Qt's per-user INI location for
    organisation "Lipspace", application "lipspace" (found without opening that file)."""
    env = os.environ.get(CONFIG_DIR_ENV)
    if env:
        return Path(env) / "lipspace.ini"
    probe = QtCore.QSettings(QtCore.QSettings.Format.IniFormat, QtCore.QSettings.Scope.UserScope, "Lipspace",
                             "lipspace-location")  # never written: only its folder is used
    return Path(probe.fileName()).with_name("lipspace.ini")


def open_settings() -> QtCore.QSettings:
    """The user's Lipspace settings (``$LIPSPACE_CONFIG_DIR/lipspace.ini`` or Qt's user location)."""
    return QtCore.QSettings(str(settings_file()), QtCore.QSettings.Format.IniFormat)


def _not_readable(path: Path) -> str | None:
    """Why ``path`` cannot be the settings file, without opening it: a pipe (Qt would block reading it),
    a device, a folder or a huge file. None when it is fine or absent."""
    from engine.files.bounded import InputTooLargeError, NotRegularFileError, check_bounded

    try:
        check_bounded(path, limit=MAX_SETTINGS_BYTES, what="settings file")
    except (FileNotFoundError, NotADirectoryError):
        return None
    except NotRegularFileError as exc:
        return f"it is {exc.kind}, not a settings file"
    except InputTooLargeError as exc:
        return f"it holds {exc.size} bytes, far more than window settings take"
    except OSError as exc:
        return exc.strerror or str(exc)
    return None


class WindowSettings:
    """Geometry, dock layout and recent files of the main window.

    Parameters
    ----------
    settings : QtCore.QSettings, optional
        Where to keep them (default :func:`open_settings`).
    """

    def __init__(self, settings: QtCore.QSettings | None = None):
        #: what was wrong with a damaged settings file set aside at start (one sentence each)
        self.set_aside: list[str] = []
        if settings is None:  # checked before Qt opens it: QSettings blocks for good on a pipe
            path = settings_file()
            why = _not_readable(path)
            if why is not None:
                self._move_aside(why, path)
                if _not_readable(path) is not None:  # could not be moved: this run keeps its settings elsewhere
                    import tempfile

                    path = Path(tempfile.mkdtemp(prefix="lipspace-settings-")) / "lipspace.ini"
            settings = QtCore.QSettings(str(path), QtCore.QSettings.Format.IniFormat)
        self.qsettings = settings
        why = self.damage()
        if why is not None:
            self._move_aside(why)

    # ------------------------------------------------------------------ damaged files
    def damage(self) -> str | None:
        """What is wrong with the settings file (None: nothing, or no file yet)."""
        from engine.files.bounded import read_bounded

        s = self.qsettings
        path = Path(s.fileName())
        why = _not_readable(path)
        if why is not None:
            return why
        try:
            raw = read_bounded(path, limit=MAX_SETTINGS_BYTES, what="settings file")
        except (OSError, ValueError):
            return None  # not written yet (or not a file: Qt's native formats)
        if b"\0" in raw:
            return "it holds binary data, not INI text"
        try:
            raw.decode("utf-8")
        except UnicodeDecodeError as exc:
            return f"byte {exc.start} is not UTF-8 text"
        if "" in s.allKeys():
            return "it holds lines that are not 'key=value' settings"
        for key in ("window/geometry", "window/state"):
            v = s.value(key)
            if v is not None and not isinstance(v, QtCore.QByteArray):
                return f"{key} is {str(v)[:30]!r}, not saved window data"
        v = s.value("window/layout_version")
        if v is not None:
            try:
                int(v)
            except (TypeError, ValueError):
                return f"window/layout_version is {str(v)[:30]!r}, not a number"
        v = s.value("recent/files")
        if v is not None and not isinstance(v, str) and not (isinstance(v, list) and all(isinstance(x, str)
                                                                                          for x in v)):
            return f"recent/files is {str(v)[:30]!r}, not a list of files"
        return None

    def _move_aside(self, why: str, path: Path | None = None) -> None:
        """Move the damaged file to ``<name>.damaged-<time>`` and start from empty settings."""
        import time

        before = path is not None  # found before Qt opened it: nothing to clear or reopen
        path = Path(self.qsettings.fileName()) if path is None else path
        dest = path.with_name(f"{path.name}.damaged-{time.strftime('%Y%m%d-%H%M%S')}")
        try:
            os.replace(path, dest)
            self.set_aside.append(f"the window settings {path} were damaged ({why}); they were moved to {dest} and "
                                  "the window starts with its default layout")
        except OSError as exc:
            self.set_aside.append(f"the window settings {path} are damaged ({why}) and could not be moved aside "
                                  f"({exc.strerror or exc}); they are ignored")
            if not before:
                self.qsettings.clear()  # none of its values is used
            return
        if not before:
            self.qsettings = QtCore.QSettings(str(path), QtCore.QSettings.Format.IniFormat)

    # ------------------------------------------------------------------ layout
    def save_layout(self, window) -> None:
        """Remember ``window``'s geometry and dock layout."""
        s = self.qsettings
        s.setValue("window/geometry", window.saveGeometry())
        s.setValue("window/state", window.saveState(LAYOUT_VERSION))
        s.setValue("window/layout_version", LAYOUT_VERSION)
        s.setValue("window/docks", dock_names(window))
        s.sync()

    def restore_layout(self, window) -> bool:
        """Restore what :meth:`save_layout` kept; False when nothing (usable) was saved."""
        s = self.qsettings
        geometry, state = s.value("window/geometry"), s.value("window/state")
        try:
            version = int(s.value("window/layout_version", -1))
        except (TypeError, ValueError):
            version = -1
        if not isinstance(geometry, QtCore.QByteArray) or not isinstance(state, QtCore.QByteArray):
            return False
        if version != LAYOUT_VERSION or s.value("window/docks") != dock_names(window):
            return False
        ok = window.restoreGeometry(geometry)
        return bool(window.restoreState(state, LAYOUT_VERSION)) and bool(ok)

    # ------------------------------------------------------------------ recent files
    def recent_files(self) -> list[str]:
        """Recently opened files, most recent first (at most :data:`MAX_RECENT`)."""
        v = self.qsettings.value("recent/files", [])
        if isinstance(v, str):  # QSettings gives one string for a one-element list in INI files
            v = [v]
        if not isinstance(v, list):
            return []
        return [str(p) for p in v if p][:MAX_RECENT]

    def add_recent(self, path) -> list[str]:
        """Put ``path`` (made absolute) first in the recent files; returns the new list."""
        p = str(Path(path).resolve())
        files = [p] + [f for f in self.recent_files() if f != p]
        self.qsettings.setValue("recent/files", files[:MAX_RECENT])
        self.qsettings.sync()
        return files[:MAX_RECENT]

    def remove_recent(self, path) -> None:
        p = str(Path(path).resolve())
        self.qsettings.setValue("recent/files", [f for f in self.recent_files() if f != p])
        self.qsettings.sync()

    def clear_recent(self) -> None:
        self.qsettings.setValue("recent/files", [])
        self.qsettings.sync()
