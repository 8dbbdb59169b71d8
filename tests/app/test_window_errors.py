"""Error messages in plain language: one mapping from exceptions to what the user reads, checked with broken
files (random bytes, a truncated manifold, stored Python objects) through the loader and in the window."""
from __future__ import annotations

import numpy as np
import pytest

from app.out_of_memory import MEMORY_HINT
from app.user_messages import UserError, looks_technical, plain_errors, user_message

TECHNICAL = ("BadZipFile", "allow_pickle", "Error", "Traceback", "Exception", "pickled", "KeyError", "zipfile")


@pytest.fixture(scope="module")
def broken_files(app_manifold, tmp_path_factory):
    d = tmp_path_factory.mktemp("broken")
    rng = np.random.default_rng(0)
    (d / "random.npz").write_bytes(rng.bytes(4000))
    good = d / "good.npz"
    app_manifold.save(good)
    data = good.read_bytes()
    (d / "truncated.npz").write_bytes(data[: len(data) // 3])
    np.savez(d / "objects.npz", manifold_version=np.array(1), x=np.array([{"a": 1}], dtype=object))
    (d / "random.npy").write_bytes(rng.bytes(4000))
    (d / "random.mat").write_bytes(rng.bytes(4000))
    return d


def _load_error(path):
    from app.files.source_loading import load_source

    with pytest.raises(Exception) as info:
        load_source(path)
    return info.value


@pytest.mark.parametrize("name, says", [
    ("random.npz", "damaged or incomplete"),
    ("truncated.npz", "damaged or incomplete"),
    ("objects.npz", "not a file Lipspace wrote"),
    ("random.npy", "random.npy"),
    ("random.mat", "random.mat"),
])
def test_broken_files_get_a_plain_message(broken_files, name, says):
    exc = _load_error(broken_files / name)
    msg = user_message(exc)
    assert says in msg and name in msg
    assert not any(word in msg for word in TECHNICAL), msg
    assert not looks_technical(msg)


def test_unexpected_failures_never_show_a_class_name():
    for exc in (KeyError("manifold_version"), TypeError("'NoneType' object is not subscriptable"),
                IndexError("index 5 is out of bounds for axis 0 with size 3"), RuntimeError("numpy ndarray")):
        msg = user_message(exc, doing="open the file", path="/data/x.npz")
        assert "x.npz" in msg and "could not open the file" in msg
        assert not looks_technical(msg) and "NoneType" not in msg and "axis 0" not in msg
    inner = user_message(TypeError("unsupported operand type(s) for +: 'int' and 'str'"), doing="synthesise")
    assert inner.startswith("Lipspace could not synthesise: something unexpected") and "operand" not in inner
    assert "no such file" in user_message(FileNotFoundError(2, "No such file or directory", "/data/y.npz"))
    # out of memory: the same text as a worker task's (app.out_of_memory.memory_message), with the size
    oom = user_message(MemoryError("Unable to allocate 15.6 GiB for an array with shape (461000, 4540)"))
    assert oom.startswith("Lipspace ran out of memory while trying to open the file: it needed 16.8 GB more at once")
    assert oom.endswith(MEMORY_HINT) and not looks_technical(oom) and "allocate" not in oom
    assert user_message(MemoryError(), doing="synthesise") == (
        f"Lipspace ran out of memory while trying to synthesise. {MEMORY_HINT}")
    # a message the engine wrote for the user keeps its file, place and expectation
    plain = "/d/a.csv, line 3: expected 4 numbers, got 2"
    assert user_message(ValueError(plain)) == plain
    assert user_message(ValueError("/d/a.npz: not a readable .npz file (BadZipFile: File is not a zip file)")
                        ).startswith("a.npz is damaged")


def test_plain_errors_wraps_a_task_and_lets_cancel_through():
    from engine.progress import Cancelled

    def bad(_progress):
        raise KeyError("frames")

    with pytest.raises(UserError) as info:
        plain_errors(bad, doing="open the file", path="c.npz")(None)
    assert "c.npz" in str(info.value) and not looks_technical(str(info.value))

    def cancelled(_progress):
        raise Cancelled("stop")

    with pytest.raises(Cancelled):
        plain_errors(cancelled)(None)


@pytest.mark.gui
@pytest.mark.parametrize("name", ["random.npz", "truncated.npz", "objects.npz"])
def test_the_window_shows_the_plain_message_in_its_dialog(qapp, qtbot, tmp_path, broken_files, name):
    from PySide6 import QtCore, QtWidgets

    from app.main_window import MainWindow
    from app.window_settings import WindowSettings

    w = MainWindow(settings=WindowSettings(QtCore.QSettings(str(tmp_path / "s.ini"),
                                                            QtCore.QSettings.Format.IniFormat)))
    w.show()
    try:
        runner = w.open_source(str(broken_files / name))
        qtbot.waitUntil(lambda: runner.state != "running", timeout=30000)
        assert runner.state == "failed"
        box = w.findChild(QtWidgets.QMessageBox, "error_dialog")
        assert box is not None and box.isVisible()
        text = box.text() + box.informativeText() + box.detailedText()
        assert name in text and not any(word in text for word in TECHNICAL), text
        assert w.settings.recent_files() == []  # a file that failed is not offered again
        box.close()
    finally:
        w.close()
