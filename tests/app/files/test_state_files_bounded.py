"""Session, autosave and settings files are checked against one schema and read only when they are small
regular files (issue 45, class 3): a damaged field is refused naming it, a FIFO or /dev/zero never hangs or
fills memory, an autosave marker is matched to the process that wrote it."""
from __future__ import annotations

import json
import os
import subprocess
import sys
import time

import pytest

from app.files.autosave import Autosaver, pid_alive
from app.files.session import SessionError, load_session


def _session(tmp_path, name="s.lipspace.json", **fields):
    p = tmp_path / name
    p.write_text(json.dumps({"lipspace_session": 2, "source": {"path": None, "preset": "small"}, **fields}))
    return p


@pytest.mark.parametrize("fields, field, what", [
    ({"selection": "x"}, "selection", "an object"),
    ({"selection": [3]}, "selection", "an object"),
    ({"selection": {"frame": "7"}}, "selection.frame", "a non-negative integer"),
    ({"source": {"preset": 5}}, "source.preset", "a preset name"),
    ({"extra": {"editor": {"oracle": "yes"}}}, "extra.editor.oracle", "true or false"),
    ({"synthetic": {"label": "x"}}, "synthetic.rate", "present"),
    ({"targets": {"labels": ["a"], "n_frames": 1, "rate": 60, "phones": [[0, 1]]}}, "targets.phones[0]",
     "[start, end, label]"),
    ({"arrays": {"file": "a.npz", "sha256": "xyz"}}, "arrays.sha256", "a SHA-256"),
    ({"phone_filter": ["a", 3]}, "phone_filter[1]", "a string"),
    ({"color_field": 3}, "color_field", "a field name"),
    ({"field_filter": [["condition", 1]]}, "field_filter[0]", "a [field, level] pair"),
    ({"extra": {"signals": "on"}}, "extra.signals", "an object or null"),
    ({"extra": {"compare": {"levels": "a, b"}}}, "extra.compare.levels", "an array of level names"),
    ({"extra": {"compare": {"n_permutations": 0}}}, "extra.compare.n_permutations", "a whole number of permutations"),
])
def test_every_field_is_checked_against_the_schema(tmp_path, fields, field, what):
    with pytest.raises(SessionError, match=rf"field '{__import__('re').escape(field)}' must be "
                                           rf"{__import__('re').escape(what)}.*damaged"):
        load_session(_session(tmp_path, **fields))


def test_missing_fields_get_their_defaults(tmp_path):
    d = load_session(_session(tmp_path))
    assert d["selection"] == {"frame": None, "state": None, "target": None} and d["cameras"] == {}
    assert d["extra"] == {"editor": {"text": None, "method": None, "source": None, "oracle": True, "sound": True,
                                    "words": []}, "signals": None, "compare": None}


def test_files_that_are_not_small_regular_files_are_refused_without_reading(tmp_path):
    fifo = tmp_path / "f.lipspace.json"
    os.mkfifo(fifo)
    with pytest.raises(SessionError, match="is a pipe"):
        load_session(fifo)
    big = tmp_path / "big.lipspace.json"
    with open(big, "wb") as fh:
        fh.truncate(6 * 2**30)
    with pytest.raises(SessionError, match="6.4 GB is more than can be read here"):
        load_session(big)
    meta = {"synthetic": {"label": "x", "rate": 60.0}}
    for name, make in (("fa", lambda p: os.mkfifo(p)), ("za", lambda p: p.symlink_to("/dev/zero"))):
        make(tmp_path / f"{name}.lipspace.npz")
        s = _session(tmp_path, f"{name}.lipspace.json", arrays={"file": f"{name}.lipspace.npz", "sha256": "0" * 64},
                     **meta)
        with pytest.raises(SessionError, match=r"its arrays file .* cannot be read \(is a (pipe|device)"):
            load_session(s)


def _dead_pid():
    p = subprocess.Popen([sys.executable, "-c", "pass"])
    p.wait()
    return p.pid


def test_a_marker_naming_a_process_that_started_long_before_it_is_a_dead_run(tmp_path):
    """pid 1 runs (it started at boot): a marker naming it was never offered nor said."""
    a = tmp_path / "autosave"
    a.mkdir()
    (a / "running-1-5.json").write_text(json.dumps({"pid": 1, "started": time.time() - 30}))
    (a / "autosave-1-5.lipspace.json").write_text(json.dumps({"lipspace_session": 2}))
    saver = Autosaver(a)
    rec = saver.begin()
    assert rec is not None and rec.pid == 1
    saver.finish()
    from app.files.autosave import _started_at

    began = _started_at(os.getpid())
    if began is not None:  # Linux: this process, matched by when it started
        assert pid_alive(os.getpid(), started=began + 1) and not pid_alive(os.getpid(), started=began + 3600)


def test_an_autosave_marker_that_is_a_fifo_is_set_aside(tmp_path):
    os.mkfifo(tmp_path / "running-4242-1.json")
    saver = Autosaver(tmp_path)
    assert saver.begin() is None
    (note,) = saver.set_aside
    assert "is damaged (not readable JSON" in note and "is a pipe" in note
    saver.finish()


def test_a_settings_file_that_is_a_fifo_is_set_aside_before_qt_opens_it(tmp_path, monkeypatch):
    pytest.importorskip("PySide6")
    from app.window_settings import WindowSettings

    monkeypatch.setenv("LIPSPACE_CONFIG_DIR", str(tmp_path))
    os.mkfifo(tmp_path / "lipspace.ini")
    w = WindowSettings()  # QSettings blocks for good reading a pipe
    assert "is a pipe (FIFO), not a settings file" in w.set_aside[0] and w.recent_files() == []
    assert [p.name.startswith("lipspace.ini.damaged-") for p in tmp_path.iterdir()] == [True]
