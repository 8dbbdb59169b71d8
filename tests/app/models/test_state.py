"""AppState, its events and the derived colourings: pure Python, no display."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.colouring import UNREACHABLE_RGB, point_colors
from app.models.state import DEFAULT_HORIZON_MS, AppState, Event, frame_phones, knn_density, original_trajectory


# ----------------------------------------------------------------------------- Event
def test_event_calls_in_order_and_disconnects():
    ev, got = Event("x"), []
    a = ev.connect(lambda v: got.append(("a", v)))
    ev.connect(lambda v: got.append(("b", v)))
    ev.emit(1)
    ev.disconnect(a)
    ev.emit(2)
    assert got == [("a", 1), ("b", 1), ("b", 2)]
    with pytest.raises(ValueError, match="not connected"):
        ev.disconnect(a)
    with pytest.raises(TypeError):
        ev.connect(3)


def test_event_propagates_callback_exceptions():
    ev, got = Event("boom"), []

    def bad(_v):
        raise RuntimeError("view broke")

    ev.connect(bad)
    ev.connect(got.append)
    with pytest.raises(RuntimeError, match="view broke"):
        ev.emit(5)
    assert got == []  # nothing after the failing callback ran silently


# ----------------------------------------------------------------------------- selection
def _record(state, *names):
    log = []
    for n in names:
        getattr(state.events, n).connect(lambda *v, n=n: log.append((n, v[0] if len(v) == 1 else v)))
    return log


def test_select_frame_sets_state_and_switches_to_distance(app_manifold):
    s = AppState(app_manifold)
    log = _record(s, "frame", "state", "color_mode")
    s.select_frame(123)
    lab = int(app_manifold.states_.labels_[123])
    assert (s.frame, s.state) == (123, lab)
    assert ("frame", 123) in log and ("state", lab) in log
    assert s.color_mode == "distance"  # clicking colours the hemisphere
    log.clear()
    s.select_frame(123)  # no change, no events
    assert log == []
    s.set_color_mode("class")
    s.set_hemisphere("off")
    s.select_frame(5)
    assert s.color_mode == "class"  # hemisphere off: the colouring is left alone


def test_select_frame_validates(app_manifold):
    s = AppState(app_manifold)
    with pytest.raises(IndexError, match="out of range"):
        s.select_frame(app_manifold.Fy_.shape[0])
    with pytest.raises(TypeError):
        s.select_frame(1.5)
    with pytest.raises(ValueError, match="hemisphere"):
        s.set_hemisphere("sideways")
    with pytest.raises(ValueError, match="colour mode"):
        s.set_color_mode("rainbow")
    with pytest.raises(RuntimeError, match="no manifold"):
        AppState().select_frame(0)


def _reachable_pair(m):
    g = m.states_
    for a in range(g.centroids_.shape[0]):
        d = g.future(a)
        far = np.flatnonzero(np.isfinite(d) & (d >= 3))
        if far.size:
            return a, int(far[0]), d
    pytest.skip("no pair of states 3+ hops apart")


def test_path_mode_second_click_sets_target_and_path(app_manifold):
    m = app_manifold
    a, b, d = _reachable_pair(m)
    fa = int(np.flatnonzero(m.states_.labels_ == a)[0])
    fb = int(np.flatnonzero(m.states_.labels_ == b)[0])
    s = AppState(m)
    paths = _record(s, "path")
    s.set_path_mode(True)
    s.select_frame(fa)
    assert s.target is None
    s.select_frame(fb)  # path mode: the second click is the target
    assert (s.frame, s.state, s.target) == (fa, a, b)
    assert s.path[0] == a and s.path[-1] == b and len(s.path) - 1 == int(d[b])
    assert len(paths) == 1 and np.array_equal(paths[0][1], s.path)
    # every step is an edge of the graph
    A = m.states_.adjacency_
    assert all(A[i, j] for i, j in zip(s.path[:-1], s.path[1:]))
    # a plain (non-path) selection of a new source clears target and path
    s.set_path_mode(False)
    s.select_frame(fb)
    assert s.target is None and s.path is None


def test_shift_click_overrides_path_mode(app_manifold):
    m = app_manifold
    a, b, _ = _reachable_pair(m)
    s = AppState(m)
    s.select_state(a)
    assert s.frame is None and s.state == a
    s.select_frame(int(np.flatnonzero(m.states_.labels_ == b)[0]), as_target=True)
    assert s.target == b and s.state == a


def test_hemisphere_off_marks_only_the_selected_state(app_manifold):
    m = app_manifold
    s = AppState(m)
    s.set_hemisphere("off")
    s.select_frame(50)
    c = point_colors("distance", m, s)
    mine = m.states_.labels_ == s.state
    assert np.all(c.values[mine] == 0) and np.isnan(c.values[~mine]).all()
    np.testing.assert_allclose(c.rgb[~mine][0], UNREACHABLE_RGB, atol=1e-6)
    assert len(np.unique(c.rgb[mine], axis=0)) == 1 and not np.allclose(c.rgb[mine][0], UNREACHABLE_RGB)


def test_utterance_trajectory_and_playback(app_manifold):
    m = app_manifold
    u = m.corpus_.utterances[2]
    s = AppState(m)
    log = _record(s, "trajectory", "playing", "playback")
    with pytest.raises(RuntimeError, match="nothing to play"):
        s.set_playback(0)
    s.set_utterance(u.id)
    assert s.original.label == u.id and len(s.original) == u.n_frames
    assert np.array_equal(s.original.frames, np.arange(u.start, u.stop))
    assert np.array_equal(s.original.Y, m.Fy_[u.start:u.stop])
    s.set_playing(True)
    s.set_playback(4)
    assert s.playing and s.playback == 4
    with pytest.raises(IndexError):
        s.set_playback(u.n_frames)
    s.set_utterance(None)  # clears trajectories, stops playback
    assert s.original is None and not s.playing and s.playback is None
    assert [n for n, _ in log].count("trajectory") == 2
    with pytest.raises(KeyError):
        s.set_utterance("no-such-utterance")


def test_set_manifold_clears_selection(app_manifold):
    s = AppState(app_manifold)
    s.select_frame(3)
    s.set_visible_phones(["m"])
    s.set_manifold(app_manifold, source={"path": None, "preset": "small"})
    assert (s.frame, s.state, s.target, s.path) == (None, None, None, None)
    assert s.visible_phones == frozenset() and s.source["preset"] == "small"


def test_visible_phones_and_component(app_manifold):
    s = AppState(app_manifold)
    log = _record(s, "visible_phones", "component")
    s.set_phone_visible("m", True)
    s.set_phone_visible("p", True)
    s.set_phone_visible("m", False)
    assert s.visible_phones == {"p"}
    s.set_component(0)
    with pytest.raises(IndexError):
        s.set_component(int(app_manifold.shape_.n_components_))
    assert log[-1] == ("component", 0) and len(log) == 4


# ----------------------------------------------------------------------------- derived data
def test_knn_density_is_higher_in_a_dense_cluster():
    rng = np.random.default_rng(0)
    Y = np.vstack([rng.normal(0, 0.1, (200, 3)), rng.normal(5, 2.0, (200, 3))])
    d = knn_density(Y, k=8)
    assert d.shape == (400,) and d.dtype == np.float32
    assert np.median(d[:200]) > np.median(d[200:]) + 3


def test_frame_phones_cover_the_alignment(app_manifold):
    c = app_manifold.corpus_
    ph = frame_phones(c)
    u = c.utterances[0]
    p = u.phones[len(u.phones) // 2]
    assert ph[c.time_to_frame(u, p.mid)] == p.label
    assert ph.shape == (c.n_frames,)


def test_original_trajectory_rows(app_manifold):
    m = app_manifold
    u = m.corpus_.utterances[1]
    t = original_trajectory(m, u.id)
    np.testing.assert_array_equal(t.Fx, m.Fx_[u.start:u.stop])
    assert t.rate == m.corpus_.rate


def test_state_picking_session_and_explore_cli_are_qt_free():
    import subprocess
    import sys

    code = ("import sys, app.models.state, app.models.picking, app.files.session, app.cli.explore\n"
            "gui = ('PySide6', 'vtkmodules', 'pyvista', 'pyvistaqt')\n"
            "bad = sorted(m for m in sys.modules if m.split('.')[0] in gui)\n"
            "print(','.join(bad))\n")
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120,
                       cwd=str(__import__("pathlib").Path(__file__).resolve().parents[3]))
    assert r.returncode == 0, r.stderr
    assert r.stdout.strip() == ""


# ----------------------------------------------------------------------------- batches
def _changes(state):
    log = []
    state.events.changed.connect(log.append)
    return log


def test_one_click_is_one_changed_event(app_manifold):
    s = AppState(app_manifold)
    changes = _changes(s)
    fields = _record(s, "frame", "state", "target", "path", "color_mode")
    s.select_frame(123)  # frame, state and the switch to distance colours: one action
    assert changes == [frozenset({"frame", "state", "color_mode"})]
    assert [n for n, _ in fields] == ["frame", "state", "color_mode"]  # each field event once, final values
    assert dict(fields)["state"] == s.state and dict(fields)["color_mode"] == "distance"
    changes.clear()
    s.select_frame(123)  # nothing changed: nothing emitted
    assert changes == []
    a, b, _d = _reachable_pair(app_manifold)
    s.select_state(a)
    changes.clear()
    s.set_target(b)  # target and path together
    assert changes == [frozenset({"target", "path"})]


def test_batch_groups_nested_changes_and_flushes_on_error(app_manifold):
    s = AppState(app_manifold)
    changes = _changes(s)
    frames = _record(s, "frame")
    with s.batch():
        s.select_frame(5)
        with s.batch():
            s.set_hemisphere("past")
            s.select_frame(6)
        assert changes == [] and frames == []  # held until the outermost batch ends
    assert changes == [frozenset({"frame", "state", "color_mode", "hemisphere"})]
    assert frames == [("frame", 6)]  # once, with the final value
    changes.clear()
    with pytest.raises(IndexError):
        with s.batch():
            s.set_color_mode("class")
            s.select_frame(10 ** 9)
    assert s.color_mode == "class" and changes == [frozenset({"color_mode"})]  # what did change is announced


def test_changes_made_by_observers_join_the_same_changed_event(app_manifold):
    s = AppState(app_manifold)
    changes = _changes(s)
    # a view that reacts to a new state by choosing a path target (changes made while events are sent)
    s.events.state.connect(lambda st: s.set_path_mode(True) if st is not None else None)
    s.select_frame(50)
    assert changes == [frozenset({"frame", "state", "color_mode", "path_mode"})]


def test_derived_data_prepared_ahead_is_used_by_every_state(app_manifold):
    from app.models.state import prepare_derived

    m, stages = app_manifold, []
    prepare_derived(m, lambda st, d, t: stages.append((st, d, t)))  # as the loading worker does
    assert stages[0] == ("preparing the views", 0, 4) and stages[-1] == ("preparing the views", 4, 4)
    a, b = AppState(), AppState(m)
    a.set_manifold(m)
    assert a.density is b.density and a.clusters is b.clusters and a.cloud is b.cloud  # computed once, ahead
    assert a.phone_codes is b.phone_codes and a.cloud.whole  # every frame of the small talker is drawn
    np.testing.assert_array_equal(a.density, knn_density(m.Fy_))
    np.testing.assert_array_equal(a.phones, frame_phones(m.corpus_))
    # the prepared palette is each state's own copy: a colour one session gives stays out of another's
    assert a.palette is not b.palette and a.palette.levels("phone") == b.palette.levels("phone")
    a.palette.colour("phone", "zz-only-in-a")
    assert "zz-only-in-a" not in b.palette.levels("phone") and "zz-only-in-a" not in AppState(m).palette.levels("phone")


# ----------------------------------------------------------------------------- targets from clicked states
def test_selected_state_targets_are_inserted_and_synthesis_passes_through_them(app_manifold):
    from app.models.state import TARGET_SPACING
    from engine.phonetics.targets import TargetError
    from engine.synthesis.methods import make_synthesizer

    m = app_manifold
    s = AppState(m)
    with pytest.raises(ValueError, match="no state selected"):
        s.selected_state_target(None)
    K = s.n_states
    a, b, c = 3 % K, (K // 2) % K, (K - 2) % K
    s.select_state(a)
    tg = s.selected_state_target(None)
    assert [(t.frame, t.state) for t in tg.targets] == [(0, a)] and tg.n_frames == 1
    step = int(round(TARGET_SPACING * m.corpus_.rate))
    s.select_state(b)
    tg = s.selected_state_target(tg)  # appended after the last target
    assert [(t.frame, t.state) for t in tg.targets] == [(0, a), (step, b)] and tg.n_frames == step + 1
    s.select_state(c)
    tg = s.selected_state_target(tg, frame=step // 2)  # inserted at the cursor, in frame order
    assert [(t.frame, t.state) for t in tg.targets] == [(0, a), (step // 2, c), (step, b)]
    s.select_state(a)
    tg = s.selected_state_target(tg, frame=step // 2)  # a target already there is replaced
    assert [(t.frame, t.state) for t in tg.targets] == [(0, a), (step // 2, a), (step, b)]
    # each target carries its state's X (the inverse map at the centroid)
    np.testing.assert_allclose(tg.targets[2].x, m.state_x_[b] if m.state_x_ is not None
                               else m.Fx_[m.states_.labels_ == b].mean(axis=0))
    traj = make_synthesizer("viterbi", m, strict=False).synthesize(tg)
    assert traj.warnings == []  # every gap bridged: the path is at each target's state on its frame
    assert [int(traj.states[t.frame]) for t in tg.targets] == [a, a, b]
    lin = make_synthesizer("linear", m).synthesize(tg)  # X methods pass through the states' X
    for t in tg.targets:
        np.testing.assert_allclose(lin.Fx[t.frame], t.x, rtol=1e-5, atol=1e-5)
    with pytest.raises(TargetError, match="outside the state graph"):
        from app.models.state import insert_state_target
        insert_state_target(m, tg, K)


# ----------------------------------------------------------------------------- state hygiene
def test_new_manifold_and_reset_view_restore_the_default_view(app_manifold):
    m = app_manifold
    s = AppState(m)
    s.select_frame(40)
    s.set_hemisphere("both")
    s.set_horizon(250)
    s.set_component(1)
    s.set_hover(7)
    s.set_path_mode(True)
    ph = sorted(set(s.phones.tolist()) - {""})[:2]
    s.set_phone_filter(ph)
    s.set_visible_phones(ph[:1])
    assert s.color_mode == "distance"
    changes = _changes(s)
    s.reset_view()  # Esc
    assert (s.frame, s.state, s.target, s.path, s.component, s.hover) == (None,) * 6
    assert (s.color_mode, s.hemisphere, s.horizon_ms, s.path_mode) == ("density", "future", DEFAULT_HORIZON_MS, False)
    assert s.phone_filter == frozenset() and s.visible_phones == frozenset()
    assert len(changes) == 1 and {"color_mode", "hemisphere", "horizon_ms", "component", "hover"} <= changes[0]
    # a new file: the same defaults, whatever the previous file showed
    s.select_frame(40)
    s.set_color_mode("phone")
    s.set_horizon(None)
    s.set_manifold(m)
    assert (s.color_mode, s.horizon_ms, s.state, s.hover) == ("density", DEFAULT_HORIZON_MS, None, None)


def test_a_click_leaves_the_component_view(app_manifold):
    s = AppState(app_manifold)
    s.set_component(0)
    s.select_frame(12)  # the lip view follows clicks again: it shows the clicked frame, not component 1
    assert s.component is None and s.frame == 12
    s.set_component(2)
    s.select_state(3)
    assert s.component is None


def test_horizon_phone_filter_and_hover_validate(app_manifold):
    s = AppState(app_manifold)
    with pytest.raises(ValueError, match="outside 0..1000 ms"):
        s.set_horizon(-5)
    with pytest.raises(TypeError, match="milliseconds"):
        s.set_horizon("100")
    with pytest.raises(ValueError, match="unknown phone.*zz"):
        s.set_phone_filter(["zz"])
    with pytest.raises(IndexError, match="hovered frame"):
        s.set_hover(app_manifold.Fy_.shape[0])
    s.set_horizon(None)
    assert s.horizon_ms is None


# ----------------------------------------------------------------------------- the field table
def test_every_field_is_declared_once_with_its_default_and_event(app_manifold):
    from app.models.state import FIELDS

    names = [f.name for f in FIELDS]
    assert len(names) == len(set(names))
    fresh = AppState()
    for f in FIELDS:
        assert getattr(fresh, f.name) == f.default  # a new state holds every default (no manifold: no palette)
        assert hasattr(fresh.events, f.event_name)
    # the events are the fields' events and ``changed``, nothing declared beside the table
    assert set(fresh.events.NAMES) == {f.event_name for f in FIELDS}
    # a new manifold returns every field but the manifold to its default, each change announced once
    s = AppState(app_manifold)
    s.select_frame(40)
    s.set_color_mode("phone")
    s.set_horizon(300)
    s.set_utterance(app_manifold.corpus_.utterances[0].id)
    s.set_playback(1)
    changes = _changes(s)
    s.set_manifold(app_manifold)
    for f in FIELDS:
        if f.name not in ("manifold", "palette"):
            assert getattr(s, f.name) == f.default or getattr(s, f.name) is f.default, f.name
    assert s.palette.levels("phone")[:3] == AppState(app_manifold).palette.levels("phone")[:3]  # the corpus's own
    assert len(changes) == 1
    assert {"manifold", "frame", "state", "color_mode", "horizon_ms", "utterance", "trajectory",
            "playback"} <= changes[0]


def test_reset_view_touches_only_view_fields(app_manifold):
    from app.models.state import FIELDS

    s = AppState(app_manifold)
    s.set_utterance(app_manifold.corpus_.utterances[0].id)
    s.select_frame(40)
    s.set_component(1)
    kept = {f.name: getattr(s, f.name) for f in FIELDS if not f.view}
    s.reset_view()
    for f in FIELDS:
        if f.view:
            assert getattr(s, f.name) == f.default, f.name
        else:  # the utterance and its trajectories stay
            assert getattr(s, f.name) is kept[f.name], f.name
    assert s.utterance is not None and s.original is not None


def test_a_field_check_runs_on_every_path_that_sets_it(app_manifold):
    """The table's check is the one place a value is validated: a setter that forgets it cannot exist."""
    from app.models.state import FIELDS

    s = AppState(app_manifold)
    K = int(app_manifold.states_.centroids_.shape[0])
    for call, err, match in ((lambda: s.set_target(K), IndexError, "target state"),
                             (lambda: s.select_state(K), IndexError, "state"),
                             (lambda: s.set_hemisphere("sideways"), ValueError, "hemisphere must be one of"),
                             (lambda: s.set_color_mode("plaid"), ValueError, "colour mode must be one of"),
                             (lambda: s._set("frame", -1), IndexError, "frame -1 out of range"),
                             (lambda: s._set("color_mode", "plaid"), ValueError, "colour mode")):
        before = {f.name: getattr(s, f.name) for f in FIELDS}
        with pytest.raises(err, match=match):
            call()
        assert all(getattr(s, n) is v for n, v in before.items())  # a refused value leaves every field as it was
    with pytest.raises(RuntimeError, match="nothing to play"):
        s.set_playback(0)
    s.set_playing(True)  # nothing to play: refused quietly
    assert s.playing is False


# ----------------------------------------------------------------------------- view settings
def test_settings_are_announced_once_per_chosen_change_and_never_for_a_click(app_manifold):
    s = AppState(app_manifold)
    seen = []
    s.events.settings.connect(lambda before, after: seen.append((before, after)))
    s.set_color_mode("phone")
    assert seen == [({"color_mode": "density"}, {"color_mode": "phone"})]
    with s.batch():                                     # one action: one announcement, with every setting moved
        s.set_horizon(50)
        s.set_visible_phones(["p"])
        s.set_horizon(100)                              # and back: no change of the horizon
    assert seen[-1] == ({"visible_phones": frozenset()}, {"visible_phones": frozenset({"p"})})
    s.select_frame(40)                                  # a click colours by hop distance: the click's, not a choice
    assert s.color_mode == "distance" and len(seen) == 2
    s.reset_settings()                                  # the view's reset: one action
    assert seen[-1][1]["color_mode"] == "density" and s.frame == 40   # the selection stays
    s.apply_settings(seen[-1][0])                       # what undo does
    assert s.color_mode == "distance" and s.visible_phones == {"p"}
    with pytest.raises(KeyError, match="not view settings: frame"):
        s.apply_settings({"frame": 3})
    with pytest.raises(ValueError, match="outside 0..1"):
        s.set_ellipsoid_opacity(1.5)
    with pytest.raises(ValueError, match="unknown layer"):
        s.set_layer_visible("floor", False)


def test_play_a_range_stops_at_its_end(app_manifold):
    """Praat's Tab: a selection plays and stops; a frame past its end (a dropped frame) shows its last."""
    s = AppState(app_manifold)
    assert not s.play(0, 10)                            # nothing to play yet
    s.set_utterance(app_manifold.corpus_.utterances[0].id)
    n = s.n_playback
    assert s.play(5, 12) and s.playing and s.playback == 5 and s.play_stop == 12
    s.set_playback(9)
    assert s.playing and s.playback == 9
    s.set_playback(14)                                  # the clock skipped past the end
    assert not s.playing and s.playback == 11 and s.play_stop is None
    assert s.play(n - 3) and s.play_stop is None        # from the cursor to the end
    s.set_playing(False)
    assert s.play(3, 10**6) and s.play_stop is None     # a stop past the end is the end
