"""Session files round-trip without Qt."""
from __future__ import annotations

import json

import pytest

from app.session import SessionError, apply_session, load_session, save_session
from app.state import AppState


def test_session_round_trip(app_manifold, tmp_path):
    m = app_manifold
    s = AppState(m)
    s.source = {"path": None, "preset": "small"}
    uid = m.corpus_.utterances[3].id
    s.set_utterance(uid)
    s.set_hemisphere("past")
    s.select_frame(77)
    s.set_target(int(m.states_.labels_[900]))
    s.set_visible_phones(["m", "p"])
    s.set_color_mode("class")
    cams = {"manifold": [[1, 2, 3], [0, 0, 0], [0, 0, 1]]}
    path = save_session(s, tmp_path / "a.lipspace.json", cameras=cams, extra={"editor": {"text": "hello"}})
    assert not list(tmp_path.glob("*.part*"))  # written atomically, no temporary left
    d = load_session(path)
    assert d["cameras"]["manifold"] == [[1.0, 2.0, 3.0], [0.0, 0.0, 0.0], [0.0, 0.0, 1.0]]
    assert d["extra"]["editor"]["text"] == "hello"
    t = AppState(m)
    apply_session(t, d)
    assert (t.frame, t.state, t.target) == (s.frame, s.state, s.target)
    assert t.color_mode == "class" and t.hemisphere == "past"
    assert t.utterance == uid and t.visible_phones == {"m", "p"}
    assert (t.path == s.path).all()


@pytest.mark.parametrize("content, match", [
    ("not json", "not a readable"),
    ('{"a": 1}', "not a Lipspace session"),
    ('{"lipspace_session": 99}', "newer"),
    ('{"lipspace_session": 1, "color_mode": "rainbow"}', "colour mode"),
    ('{"lipspace_session": 1, "selection": {"frame": -3}}', "non-negative"),
])
def test_load_session_rejects_bad_files(tmp_path, content, match):
    p = tmp_path / "bad.json"
    p.write_text(content)
    with pytest.raises(SessionError, match=match):
        load_session(p)


def test_session_that_does_not_fit_the_manifold(app_manifold, tmp_path):
    p = tmp_path / "big.json"
    p.write_text(json.dumps({"lipspace_session": 1, "selection": {"frame": 10 ** 9}}))
    with pytest.raises(SessionError, match="does not fit"):
        apply_session(AppState(app_manifold), load_session(p))
    with pytest.raises(SessionError, match="no such session"):
        load_session(tmp_path / "missing.json")
