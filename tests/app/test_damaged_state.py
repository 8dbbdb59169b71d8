"""Damaged window state files (autosave markers and sessions, session files, the window settings) are set
aside with a message naming them, never a traceback, and the window opens."""
import json

import pytest

from app.files.autosave import Autosaver
from app.files.session import SessionError, load_session

DAMAGED_MARKERS = {
    "started text": {"pid": 4242, "started": "abc"},
    "pid text": {"pid": "x", "started": 1.0},
    "pid zero": {"pid": 0},
    "ticks float": {"pid": 4242, "start_ticks": 1.5},
    "a list": [1, 2],
    "not json": "{pid: ",
    "started infinite": {"pid": 4242, "started": 1e999},
}


def _marker(folder, name, body):
    folder.mkdir(parents=True, exist_ok=True)
    p = folder / f"running-{name}.json"
    p.write_text(body if isinstance(body, str) else json.dumps(body).replace("Infinity", "1e999"))
    return p


@pytest.mark.parametrize("case", sorted(DAMAGED_MARKERS))
def test_a_damaged_autosave_marker_is_set_aside_and_named(tmp_path, case):
    bad = _marker(tmp_path, "4242-1", DAMAGED_MARKERS[case])
    (tmp_path / "autosave-4242-1.lipspace.json").write_text("{}")
    a = Autosaver(tmp_path)
    assert a.begin() is None  # no traceback, nothing offered
    (note,) = a.set_aside
    assert str(bad) in note and "is damaged" in note and "moved to" in note
    assert not bad.exists() and [p.name.startswith(bad.name) for p in (tmp_path / "damaged").iterdir()] == [True]
    assert a.marker.exists()  # this run's marker is written as usual
    a.finish()


def _session(tmp_path, **fields):
    d = {"lipspace_session": 2, "source": {"path": None, "preset": "small"}, **fields}
    p = tmp_path / "s.lipspace.json"
    p.write_text(json.dumps(d).replace("NaN", "NaN"))
    return p


@pytest.mark.parametrize("fields, field", [
    ({"extra": [1, 2]}, "extra"),
    ({"extra": {"editor": "text"}}, "extra.editor"),
    ({"extra": {"editor": {"text": 5}}}, "extra.editor.text"),
    ({"cameras": {"manifold": [[float("nan"), 0, 1], [0, 0, 0], [0, 1, 0]]}}, "cameras.manifold"),
    ({"cameras": {"manifold": [[0, 0, 1], [0, 0, 1], [0, 1, 0]]}}, "cameras.manifold"),
    ({"cameras": {"lips": [[0, 0, 1], [0, 0, 0], [0, 0, 0]]}}, "cameras.lips"),
    ({"cameras": [1, 2, 3]}, "cameras"),
    ({"visible_phones": "aa"}, "visible_phones"),
    ({"horizon_ms": "soon"}, "horizon_ms"),
    ({"component": -1}, "component"),
    ({"path_mode": "yes"}, "path_mode"),
    ({"utterance": 3}, "utterance"),
    ({"synthetic": [1]}, "synthetic"),
])
def test_a_session_with_damaged_fields_is_refused_naming_the_field(tmp_path, fields, field):
    p = _session(tmp_path, **fields)
    with pytest.raises(SessionError, match=rf"s.lipspace.json: field '{field}' must be .*damaged") as e:
        load_session(p)
    assert "Traceback" not in str(e.value)


def test_a_good_session_still_loads(tmp_path):
    p = _session(tmp_path, cameras={"manifold": [[0, 0, 5], [0, 0, 0], [0, 1, 0]]}, extra={"editor": {"text": "a"}},
                 horizon_ms=None, visible_phones=["aa"], component=0, path_mode=True, utterance="u1")
    assert load_session(p)["cameras"]["manifold"][0] == [0, 0, 5]


# ------------------------------------------------------------------ the window opens
@pytest.mark.gui
@pytest.mark.parametrize("how", [["--restore"], ["--no-restore"], ["--session", "GOOD"]])
def test_explore_opens_past_a_damaged_marker(app_manifold, tmp_path, monkeypatch, capsys, how, run_cli_window):
    mfile = app_manifold.save(tmp_path / "m.npz")
    state = tmp_path / "state"
    monkeypatch.setenv("LIPSPACE_STATE_DIR", str(state))
    bad = _marker(state / "autosave", "4242-1", {"pid": 4242, "started": "abc"})
    (state / "autosave" / "autosave-4242-1.lipspace.json").write_text("{}")
    good = _session(tmp_path, source={"path": str(mfile)})
    argv = ["explore", *[str(good) if a == "GOOD" else a for a in how]]
    if "--session" not in how:
        argv.insert(1, str(mfile))
    code, seen = run_cli_window(argv, ready=lambda w: w.state.manifold is not None,
                                look=lambda w: getattr(w, "last_error_message", ""))
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err, err
    assert f"lipspace explore: warning: {bad} is damaged ('started' is \"abc\"" in err, err
    assert str(bad) in seen  # said in the window too
    assert not bad.exists() and list((state / "autosave" / "damaged").iterdir())


@pytest.mark.gui
def test_explore_opens_when_its_session_or_settings_are_damaged(app_manifold, tmp_path, monkeypatch, capsys,
                                                                 run_cli_window):
    import os

    mfile = app_manifold.save(tmp_path / "m.npz")
    monkeypatch.setenv("LIPSPACE_STATE_DIR", str(tmp_path / "state"))
    ini = tmp_path / "config" / "lipspace.ini"
    ini.parent.mkdir()
    ini.write_text("[window]\ngeometry=@ByteArray(abc\nlayout_version=zz\n")
    monkeypatch.setenv("LIPSPACE_CONFIG_DIR", str(ini.parent))
    bad = _session(tmp_path, source={"path": str(mfile)}, extra=[1, 2])
    code, seen = run_cli_window(["explore", str(mfile), "--session", str(bad)],
                                ready=lambda w: w.state.manifold is not None,
                                look=lambda w: getattr(w, "last_error_message", ""))
    err = capsys.readouterr().err
    assert code == 0 and "Traceback" not in err, err
    assert f"--session {bad} was not opened" in err and "field 'extra' must be an object" in err, err
    assert f"the window settings {ini} were damaged (window/geometry" in err, err
    assert str(bad) in seen and str(ini) in seen
    assert bad.exists()  # the user's own session file stays where it is
    assert [p.name.startswith("lipspace.ini.damaged-") for p in ini.parent.iterdir() if p.name != "lipspace.ini"] \
        == [True]
    assert os.environ["LIPSPACE_CONFIG_DIR"] == str(ini.parent)


@pytest.mark.gui
def test_open_session_with_a_nan_camera_is_a_dialog(qapp, app_manifold, tmp_path, main_window_factory):
    bad = _session(tmp_path, cameras={"manifold": [[float("nan"), 0, 1], [0, 0, 0], [0, 1, 0]]})
    with main_window_factory(qapp, app_manifold) as win:
        before = win.manifold_view.camera()
        assert win._report(lambda: win.open_session(bad), "opened", "open the session") is False
        assert "cameras.manifold" in win.last_error_message and str(bad) in win.last_error_message
        assert win.manifold_view.camera() == before  # the view is not blanked
