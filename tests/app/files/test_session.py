"""Session files round-trip without Qt."""
from __future__ import annotations

import json

import numpy as np
import pytest

from app.files.session import SessionError, apply_session, load_session, save_session
from app.models.state import AppState


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
    s.set_horizon(50.0)
    s.set_phone_filter(["p", "b"])
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
    assert t.horizon_ms == 50.0 and t.phone_filter == {"p", "b"}
    assert (t.path == s.path).all()


def test_a_session_keeps_its_colours_ellipsoid_fill_and_hidden_layers(app_manifold, tmp_path):
    """Each category keeps the colour it was seen in: the palette goes into the session (a phone first
    coloured by hand keeps its colour too), with the ellipsoids' fill and the layers hidden."""
    s = AppState(app_manifold)
    s.palette.colour("phone", "zz-new")                      # a level given a colour during the session
    s.set_ellipsoid_opacity(0.65)
    s.set_layer_visible("plane", False)
    d = load_session(save_session(s, tmp_path / "c.lipspace.json"))
    t = AppState(app_manifold)
    assert t.palette.levels("phone") != s.palette.levels("phone")
    apply_session(t, d)
    assert t.palette.levels("phone") == s.palette.levels("phone")
    assert t.palette.colour("phone", "zz-new") == s.palette.colour("phone", "zz-new")
    assert t.ellipsoid_opacity == pytest.approx(0.65) and t.hidden_layers == {"plane"}
    bad = json.loads((tmp_path / "c.lipspace.json").read_text())
    bad["ellipsoid_opacity"] = 3
    (tmp_path / "bad.lipspace.json").write_text(json.dumps(bad))
    with pytest.raises(SessionError, match="ellipsoid_opacity"):
        load_session(tmp_path / "bad.lipspace.json")


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


def _edited_targets(m, uid):
    """Oracle targets of an utterance with one target dragged, as the editor leaves them."""
    from dataclasses import replace

    from engine.phonetics.targets import targets_from_utterance

    tg = targets_from_utterance(m, uid, on_collision="merge")
    ts = list(tg.targets)
    ts[1] = replace(ts[1], frame=ts[1].frame + 1 if ts[2].frame > ts[1].frame + 1 else ts[1].frame)
    ts[2] = replace(ts[2], state=None, y=None)  # a target without its oracle
    return replace(tg, targets=tuple(ts))


def test_session_keeps_synthesised_trajectory_and_edited_targets(app_manifold, tmp_path):
    from app.files.session import arrays_path
    from app.models.state import TrajectoryData

    m = app_manifold
    s = AppState(m)
    s.source = {"path": None, "preset": "small"}
    u = m.corpus_.utterances[2]
    s.set_utterance(u.id)
    rng = np.random.default_rng(0)
    n = u.stop - u.start
    syn = TrajectoryData(Y=(m.Fy_[u.start:u.stop] + rng.normal(0, 0.01, (n, m.Fy_.shape[1]))).astype(np.float32),
                         Fx=m.Fx_[u.start:u.stop] * 0.9, label="manifold", rate=m.corpus_.rate,
                         extra={"method": "manifold", "warnings": ["target 3 undershot"],
                                "target_frames": np.array([3, 9, 20])})
    s.set_trajectories(synthetic=syn)
    tg = _edited_targets(m, u.id)
    path = save_session(s, tmp_path / "b.lipspace.json", targets=tg)
    npz = arrays_path(path)
    assert npz.name == "b.lipspace.npz" and npz.is_file() and not list(tmp_path.glob("*.part*"))
    d = load_session(path)
    t = AppState(m)
    back = apply_session(t, d)
    np.testing.assert_array_equal(t.synthetic.Y, syn.Y)
    np.testing.assert_array_equal(t.synthetic.Fx, syn.Fx.astype(np.float32))
    assert (t.synthetic.label, t.synthetic.rate, t.utterance) == ("manifold", m.corpus_.rate, u.id)
    assert t.synthetic.extra["warnings"] == ["target 3 undershot"]
    np.testing.assert_array_equal(t.synthetic.extra["target_frames"], [3, 9, 20])
    assert t.original is not None and len(t.original) == n  # the utterance is back as well
    assert back == tg  # frames, labels, states, phones, n_frames, rate, source, utterance
    for a, b in zip(back.targets, tg.targets):
        for key in ("y", "x"):
            va, vb = getattr(a, key), getattr(b, key)
            assert (va is None) == (vb is None)
            if vb is not None:
                np.testing.assert_allclose(va, vb)
    # saving again without arrays removes the stale .npz
    s.set_trajectories(synthetic=None)
    save_session(s, path)
    assert not npz.exists() and load_session(path)["_synthetic"] is None


def test_session_arrays_must_match_their_json(app_manifold, tmp_path):
    from app.files.session import arrays_path

    m = app_manifold
    s = AppState(m)
    tg = _edited_targets(m, m.corpus_.utterances[0].id)
    a = save_session(s, tmp_path / "a.lipspace.json", targets=tg)
    b = save_session(s, tmp_path / "b.lipspace.json", targets=_edited_targets(m, m.corpus_.utterances[1].id))
    arrays_path(a).write_bytes(arrays_path(b).read_bytes())  # another save's arrays
    with pytest.raises(SessionError, match="does not match the session"):
        load_session(a)
    arrays_path(b).unlink()
    with pytest.raises(SessionError, match="cannot be read"):
        load_session(b)
    d = json.loads(a.read_text())
    d["arrays"]["file"] = "../elsewhere.npz"
    a.write_text(json.dumps(d))
    with pytest.raises(SessionError, match="plain .npz file name"):
        load_session(a)
    with pytest.raises(ValueError, match="is JSON"):
        save_session(s, tmp_path / "c.npz")


def test_session_arrays_from_another_manifold_are_refused(app_manifold, tmp_path):
    from dataclasses import replace

    m = app_manifold
    s = AppState(m)
    tg = _edited_targets(m, m.corpus_.utterances[0].id)
    bad = replace(tg, targets=(replace(tg.targets[0], state=10 ** 6),) + tg.targets[1:])
    p = save_session(s, tmp_path / "a.lipspace.json", targets=bad)
    with pytest.raises(SessionError, match="does not fit.*state 1000000"):
        apply_session(AppState(m), load_session(p))
    from app.models.state import TrajectoryData

    s.set_trajectories(synthetic=TrajectoryData(Y=m.Fy_[:20, :3]))  # the manifold method's 3-D path fits
    apply_session(AppState(m), load_session(save_session(s, tmp_path / "c.lipspace.json")))
    s.set_trajectories(synthetic=TrajectoryData(Y=np.zeros((20, m.Fy_.shape[1] + 1), np.float32)))
    with pytest.raises(SessionError, match="embedding dims"):
        apply_session(AppState(m), load_session(save_session(s, tmp_path / "d.lipspace.json")))
