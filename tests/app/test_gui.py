"""The explorer window on the small synthetic manifold (needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def shared_window(qapp, app_manifold, main_window_factory):
    with main_window_factory(qapp, app_manifold) as w:
        yield w


@pytest.fixture
def win(fresh_window):
    """The shared window, reset for each test (conftest's ``fresh_window``)."""
    return fresh_window


def _points(manifold, row):
    from engine.recordings.corpus import frame_points

    return frame_points(np.asarray(row, np.float32), manifold.corpus_.dims)


def _front_frame(view, Y):
    """A frame whose point is nearest the camera (never hidden behind another)."""
    cam = np.array(view.plotter.camera.position)
    return int(np.argmin(np.linalg.norm(Y - cam, axis=1)))


def _red_pixels(plotter):
    plotter.render()
    img = plotter.screenshot()
    return int(((img[..., 0] > 200) & (img[..., 1] < 60) & (img[..., 2] < 60)).sum())


def test_window_opens_with_every_view(win, app_manifold):
    m = app_manifold
    N = m.Fy_.shape[0]
    assert "synthetic talker (small)" in win.windowTitle()
    assert f"{N} frames" in win.summary_label.text()
    assert win.manifold_view.handles["points"].mesh.n_points == N
    assert win.lip_view.main.mesh.n_points == m.corpus_.n_points
    assert set(win.docks) == {"lips", "clusters", "scree", "editor", "multiples", "compare"}
    assert win.editor.utt_box.count() == len(m.corpus_.utterances)
    img = win.manifold_view.plotter.screenshot()
    assert img.std() > 5  # not blank
    grab = win.grab().toImage()
    assert grab.width() > 1000 and grab.height() > 700


def test_click_selects_frame_colours_hemisphere_and_links_lips(win, qtbot, app_manifold):
    from PySide6 import QtCore

    from app.scene import pick_display_point

    m, view, s = app_manifold, win.manifold_view, win.state
    Y = np.asarray(m.Fy_[:, :3], np.float64)
    before = win.lip_view.main.points.copy()
    s.set_horizon(None)  # every reachable state coloured (the default horizon dims states beyond it)
    i = _front_frame(view, Y)
    x, y = pick_display_point(view.plotter, Y[i])
    # a real mouse click on the VTK widget (Qt y runs down, VTK display y up from the window's bottom row)
    widget = view.plotter.interactor
    ratio = widget.devicePixelRatioF()
    height = view.plotter.render_window.GetSize()[1]
    pos = QtCore.QPoint(int(round(x / ratio)), int(round((height - 1 - y) / ratio)))
    qtbot.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, pos=pos)
    if s.frame is None:  # some VTK builds drop synthetic Qt clicks; pick through VTK's picker instead
        view.picker.pick(x, y)
    assert s.frame is not None and np.allclose(Y[s.frame], Y[i])
    assert s.state == int(m.states_.labels_[s.frame]) and s.color_mode == "distance"
    values = view.handles["points"].values
    mine = m.states_.labels_ == s.state
    assert np.all(values[mine] == 0)
    future = m.states_.future(s.state)[m.states_.labels_]
    assert np.array_equal(np.isnan(values), ~np.isfinite(future))
    np.testing.assert_allclose(values[~np.isnan(values)], future[np.isfinite(future)])
    rgb = view.handles["points"].rgb
    from app.models.colouring import FUTURE_CMAP, colormap_rgb

    hop0 = np.rint(255 * colormap_rgb(FUTURE_CMAP, 0.0)).astype(int)
    assert np.all(np.abs(rgb[mine].astype(int) - hop0) <= 1)  # hop 0: the future map's darkest colour
    # linked lip view shows the captured frame
    np.testing.assert_allclose(win.lip_view.main.points, _points(m, m.corpus_.frames[s.frame]), atol=1e-5)
    assert not np.allclose(win.lip_view.main.points, before)
    assert view.handles["local"].visible and view.handles["marker"].visible
    # past hemisphere recolours from the same state
    s.set_hemisphere("past")
    past = m.states_.past(s.state)[m.states_.labels_]
    # (past hops are shown signed, -1, -2, ...: one scale for the past and future hemispheres)
    np.testing.assert_allclose(np.nan_to_num(view.handles["points"].values, nan=999),
                               np.nan_to_num(np.where(np.isfinite(past), -past, np.nan), nan=999))
    # shift-click on a far state draws the minimum-distance path over centroids
    d = m.states_.future(s.state)
    far = int(np.flatnonzero(np.isfinite(d) & (d == np.nanmax(np.where(np.isfinite(d), d, np.nan))))[0])
    j = int(np.flatnonzero(m.states_.labels_ == far)[0])
    view._on_pick(j, Y[j], True)
    assert s.target == far and s.path is not None
    path = view.handles["path"]
    assert path.visible
    np.testing.assert_allclose(path.points, m.states_.centroids_[s.path][:, :3], atol=1e-9)
    assert f"{len(s.path) - 1} hops" in view.info.text()


def test_one_click_recolours_once_renders_once_and_keeps_the_actors(win, qapp, app_manifold):
    from PySide6 import QtCore

    from app.scene import pick_display_point

    m, view, lips, s = app_manifold, win.manifold_view, win.lip_view, win.state
    Y = np.asarray(m.Fy_[:, :3], np.float64)
    for _ in range(5):
        qapp.processEvents()
    actors = dict(view.plotter.actors)
    points = view.handles["points"]
    actor, mesh = points.actor, points.mesh
    changes, vtk_renders = [], []
    s.events.changed.connect(changes.append)
    obs = view.plotter.render_window.AddObserver("EndEvent", lambda *_a: vtk_renders.append(1))
    n_recolor, n_req, n_lip = view.n_recolors, view.renderer.n_renders, lips.renderer.n_renders
    try:
        i = _front_frame(view, Y)
        x, y = pick_display_point(view.plotter, Y[i])
        widget = view.plotter.interactor
        ratio = widget.devicePixelRatioF()
        height = view.plotter.render_window.GetSize()[1]
        pos = QtCore.QPoint(int(round(x / ratio)), int(round((height - 1 - y) / ratio)))
        QtCore.QCoreApplication.processEvents()
        from PySide6.QtTest import QTest

        QTest.mouseClick(widget, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier, pos)
        if s.frame is None:  # some VTK builds drop synthetic Qt clicks; pick through VTK's picker instead
            view.picker.pick(x, y)
        for _ in range(10):
            qapp.processEvents()
    finally:
        s.events.changed.disconnect(changes.append)
        view.plotter.render_window.RemoveObserver(obs)
    assert s.frame is not None and s.color_mode == "distance"
    assert len(changes) == 1 and {"frame", "state", "color_mode"} <= changes[0]  # one state emission
    assert view.n_recolors == n_recolor + 1  # one recolouring, not one per changed field
    assert view.renderer.n_renders == n_req + 1 and lips.renderer.n_renders == n_lip + 1  # one render request each
    assert len(vtk_renders) == 1  # and one VTK render of the manifold view
    assert points.actor is actor and points.mesh is mesh  # colours changed in place
    assert dict(view.plotter.actors) == actors and all(view.plotter.actors[k] is a for k, a in actors.items())
    assert np.isfinite(points.values).any()


def test_a_render_request_joins_the_window_paint_of_its_pass(win, qapp):
    """A view asking for a render marks its widget dirty at once, so it is painted and composed with
    the other widgets changed in the same pass: marking it from a timer let Qt compose the others
    first and the view after (two compositions of the window, ~20 ms each in software GL)."""
    from PySide6 import QtCore

    view = win.manifold_view
    for _ in range(5):
        qapp.processEvents()
    renders = []
    obs = view.plotter.render_window.AddObserver("EndEvent", lambda *_a: renders.append(1))
    try:
        n = view.renderer.n_renders
        view.renderer.request()
        win.editor.readout.setText("another widget changed in the same pass")
        view.renderer.request()  # coalesced
        assert view.renderer.pending and view.renderer.n_renders == n + 1
        # only the window's posted paint, no timer: the view is rendered in it
        QtCore.QCoreApplication.sendPostedEvents(win, int(QtCore.QEvent.Type.UpdateRequest.value))
        assert len(renders) == 1
        for _ in range(5):
            qapp.processEvents()
        assert not view.renderer.pending and len(renders) == 1 and view.renderer.n_renders == n + 1
    finally:
        view.plotter.render_window.RemoveObserver(obs)


def test_the_readouts_under_the_3d_view_never_resize_it(win, qapp, app_manifold):
    """A readout re-wrapping onto more or fewer lines resized the 3-D view above it: the cloud
    jumped under the pointer and was rendered again on a click or a hover. They share one line,
    each elided, the whole text in its tooltip."""
    view, s = win.manifold_view, win.state
    for _ in range(5):
        qapp.processEvents()
    size = view.plotter.interactor.size()
    s.select_frame(int(app_manifold.corpus_.utterances[0].start))
    s.set_hover(int(app_manifold.corpus_.utterances[0].start) + 1)
    for _ in range(5):
        qapp.processEvents()
    assert view.info.text().startswith("frame") and view.hover_label.text().startswith("under the pointer")
    assert view.info.y() == view.hover_label.y() and view.plotter.interactor.size() == size
    long = "a long readout " * 60
    view.info.setText(long)
    for _ in range(5):
        qapp.processEvents()
    assert view.plotter.interactor.size() == size and view.info.text() == long == view.info.toolTip()
    shown = super(type(view.info), view.info).text()                # what is drawn: elided at its end
    assert shown.endswith("…") and view.info.fontMetrics().horizontalAdvance(shown) <= view.info.width()


def test_playback_shows_the_frame_due_by_the_clock_and_leaves_the_cloud_alone(win, qapp, app_manifold):
    m, s, lv, view = app_manifold, win.state, win.lip_view, win.manifold_view
    u = max(m.corpus_.utterances, key=lambda u: u.stop - u.start)
    n = u.stop - u.start
    assert n > 40
    s.set_utterance(u.id)
    s.select_frame(u.start)  # the cloud shows hop distances: playback must not recolour it
    qapp.processEvents()
    now = [1000.0]
    lv.clock_source = lambda: now[0]
    rgb = view.handles["points"].rgb.copy()
    n_recolor = view.n_recolors
    try:
        s.set_playing(True)
        lv.timer.stop()  # tick by hand with the fake clock
        assert s.playback == 0
        # the fake clock measures no display latency: the picture looks ahead by the lead alone
        assert lv.clock.look_ahead_s == pytest.approx(lv.clock.lead_s) and lv.clock.lead_s > 0
        now[0] += 0.1  # 100 ms later at 60 Hz, aimed 15 ms ahead: frame 6.9 -> 7, frames 1-6 dropped
        lv._tick()
        assert s.playback == 7
        np.testing.assert_allclose(lv.main.points, _points(m, m.corpus_.frames[u.start + 7]), atol=1e-5)
        now[0] += 0.5  # 615 ms: frame 36.9 -> 37
        lv._tick()
        assert s.playback == 37
        marker = view.handles["play_o"]
        assert marker.visible and np.allclose(marker.center, m.Fy_[u.start + 37, :3])
        lv._tick()  # no time passed: the same frame, nothing redrawn
        assert s.playback == 37
        assert view.n_recolors == n_recolor and np.array_equal(view.handles["points"].rgb, rgb)
        now[0] += 60.0  # far past the end: the last frame, stopped
        lv._tick()
        assert not s.playing and s.playback == n - 1
    finally:
        lv.clock_source = __import__("time").monotonic
        s.set_playing(False)


def test_play_leaves_the_first_frames_to_the_lip_view(win, qapp, app_manifold):
    """Pressing Play after a pause does not render the manifold's playback markers at once: that
    render (25-30 ms in software GL) landed just as the clock started and held back the first lip
    frames. The markers' first render waits one throttle interval from Play."""
    import time

    m, s, view = app_manifold, win.state, win.manifold_view
    u = max(m.corpus_.utterances, key=lambda u: u.stop - u.start)
    s.set_utterance(u.id)
    qapp.processEvents()
    time.sleep(view.PLAYBACK_RENDER_INTERVAL_S + 0.05)  # idle longer than the throttle interval
    win.lip_view.timer.stop()
    try:
        t0 = time.perf_counter()
        s.set_playing(True)  # the lip view draws the shown frame in here
        win.lip_view.timer.stop()  # no lip frames: only the manifold view's request is looked at
        assert view.renderer.pending
        # due no sooner than one interval after Play (was: at once, the last render being long ago)
        due_ms = view.renderer._timer.remainingTime() + 1000 * (time.perf_counter() - t0)
        assert due_ms >= 1000 * view.PLAYBACK_RENDER_INTERVAL_S - 20, due_ms
        n = view.renderer.n_renders
        qapp.processEvents()
        assert view.renderer.n_renders == n
    finally:
        s.set_playing(False)
    qapp.processEvents()
    assert not view.renderer.pending  # stopped: the markers are drawn at once


def test_synthesise_typed_text_draws_red_trajectory(win, qtbot, app_manifold):
    m, view, s, ed = app_manifold, win.manifold_view, win.state, win.editor
    ed.set_method("manifold")
    assert ed.set_text("bob may bake a pie", source="text")
    assert len(ed.targets.targets) >= 5
    ed.synthesize()
    qtbot.waitUntil(lambda: s.synthetic is not None, timeout=30000)
    syn = view.handles["synthetic"]
    assert syn.visible and len(syn.points) == len(s.synthetic) == ed.targets.n_frames
    assert len(syn.arrows[0]) == 5                            # cones show which way it runs
    hidden = [view.handles[k] for k in ("points", "plane", "marker")]
    try:
        for h in hidden:
            h.set_visible(False)
        view._bar.SetVisibility(False)  # the colour bar's red end
        for box in view.legends.values():  # and the legend's row naming the red trajectory
            box.SetVisibility(False)
        assert _red_pixels(view.plotter) > 30  # the synthetic trajectory is red
        syn.set_visible(False)
        assert _red_pixels(view.plotter) == 0  # and nothing else is
    finally:
        for h in hidden:
            h.set_visible(True)
        view._bar.SetVisibility(True)
        view._update_legends()
        for key, box in view.legends.items():
            box.SetVisibility(bool(view.legend_rows[key]))
        syn.set_visible(True)
    # playback without an original shows the synthetic lips alone
    s.set_playback(5)
    expect = m.shape_.inverse_transform(s.synthetic.Fx[5:6])[0]
    np.testing.assert_allclose(win.lip_view.main.points, _points(m, expect), atol=1e-4)
    assert not win.lip_view.second.visible


def test_utterance_synthesis_reports_error_and_plays_side_by_side(win, qtbot, app_manifold):
    m, s, ed = app_manifold, win.state, win.editor
    u = m.corpus_.utterances[1]
    ed.set_source("utterance")
    ed.utt_box.setCurrentIndex(1)
    assert ed.load()
    assert s.utterance == u.id and win.manifold_view.handles["original"].visible
    ed.set_method("linear")
    ed.synthesize()
    qtbot.waitUntil(lambda: s.synthetic is not None, timeout=30000)
    assert "RMSE(X)" in ed.readout.text()
    err = ed.last_error
    # the same measure as `lipspace evaluate`: RMS over frames of the Euclidean error in X
    direct = np.sqrt(np.mean(np.sum((np.asarray(s.synthetic.Fx, np.float64) - m.Fx_[u.start:u.stop]) ** 2, axis=1)))
    assert err["rmse_x"] == pytest.approx(direct, rel=1e-4) and err["rmse_x"] > 0
    assert err["frames"] == u.stop - u.start and 0 < err["mean_point_error"] <= err["max_point_error"]
    s.set_playback(10)
    np.testing.assert_allclose(win.lip_view.main.points, _points(m, m.corpus_.frames[u.start + 10]), atol=1e-5)
    assert win.lip_view.second.visible
    syn10 = _points(m, m.shape_.inverse_transform(s.synthetic.Fx[10:11])[0])
    np.testing.assert_allclose(win.lip_view.second.points, syn10, atol=1e-4)
    # playing advances the frame on the timer and stops at the end
    s.set_playback(len(s.original) - 3)
    s.set_playing(True)
    qtbot.waitUntil(lambda: not s.playing, timeout=5000)
    assert s.playback == len(s.original) - 1


def test_dragging_a_target_moves_its_frame(win, qtbot):
    from PySide6 import QtCore

    ed = win.editor
    assert ed.set_text("m 0.2 aa 0.3 p 0.2", source="phones")
    tl = ed.timeline
    tl.resize(600, 80)
    f0 = ed.targets.targets[1].frame
    start = QtCore.QPoint(int(tl.marker_x(1)), int(tl.marker_y()))
    qtbot.mousePress(tl, QtCore.Qt.MouseButton.LeftButton, pos=start)
    qtbot.mouseMove(tl, start + QtCore.QPoint(40, 0))
    qtbot.mouseRelease(tl, QtCore.Qt.MouseButton.LeftButton, pos=start + QtCore.QPoint(40, 0))
    f1 = ed.targets.targets[1].frame
    assert f1 > f0 and f1 < ed.targets.targets[2].frame


def test_clicked_states_become_targets_that_synthesis_passes_through(win, qtbot, app_manifold):
    from PySide6 import QtCore

    from app.views.trajectory_editor import ADD_STATE_SHORTCUT

    m, s, ed = app_manifold, win.state, win.editor
    assert ed.set_text("m 0.2 aa 0.3 p 0.2", source="phones")
    phone_frames = [t.frame for t in ed.targets.targets]
    assert not ed.add_state_btn.isEnabled()  # nothing clicked yet
    K = s.n_states
    a, b = 2 % K, (K // 2) % K
    s.select_state(a)
    assert ed.add_state_btn.isEnabled()
    cursor = (phone_frames[0] + phone_frames[1]) // 2
    ed.timeline.set_cursor(cursor)  # the playback position
    qtbot.mouseClick(ed.add_state_btn, QtCore.Qt.MouseButton.LeftButton)
    assert [t.frame for t in ed.targets.targets] == sorted(phone_frames + [cursor])
    assert ed.targets.targets[1].state == a and ed.timeline.targets is ed.targets
    s.select_state(b)
    ed.timeline.set_cursor(None)
    win.activateWindow()
    qtbot.waitUntil(lambda: win.isActiveWindow(), timeout=5000)
    assert ADD_STATE_SHORTCUT == "Ctrl+T"
    qtbot.keyClick(ed, QtCore.Qt.Key.Key_T, QtCore.Qt.KeyboardModifier.ControlModifier)  # the shortcut
    qtbot.waitUntil(lambda: len(ed.targets.targets) == 5, timeout=5000)  # a shortcut animates the click
    last = ed.targets.targets[-1]
    assert last.state == b and last.frame > phone_frames[-1] and ed.targets.n_frames == last.frame + 1
    assert [t.state for t in ed.targets.targets] == [None, a, None, None, b]
    ed.set_method("viterbi")  # the paper's path: it moves in Y through the clicked states themselves
    s.set_trajectories(synthetic=None)
    ed.synthesize()
    qtbot.waitUntil(lambda: s.synthetic is not None, timeout=30000)
    syn = s.synthetic
    assert len(syn) == ed.targets.n_frames and syn.extra["warnings"] == []
    C = m.states_.centroids_
    for f, st in ((cursor, a), (last.frame, b)):  # the path is at the clicked state on its target frame
        np.testing.assert_allclose(syn.Y[f], C[st], rtol=1e-5, atol=1e-5)


TEXTGRID = """File type = "ooTextFile"
Object class = "TextGrid"

xmin = 0
xmax = 0.9
tiers? <exists>
size = 1
item []:
    item [1]:
        class = "IntervalTier"
        name = "phones"
        xmin = 0
        xmax = 0.9
        intervals: size = 3
        intervals [1]:
            xmin = 0
            xmax = 0.25
            text = "m"
        intervals [2]:
            xmin = 0.25
            xmax = 0.6
            text = "aa"
        intervals [3]:
            xmin = 0.6
            xmax = 0.9
            text = "p"
"""


def test_textgrid_input_and_bad_input(win, tmp_path):
    ed = win.editor
    tg = tmp_path / "mop.TextGrid"
    tg.write_text(TEXTGRID)
    assert ed.set_text(str(tg), source="textgrid")
    assert [t.label for t in ed.targets.targets] == ["m", "aa", "p"]
    assert ed.targets.n_frames == round(0.9 * win.state.manifold.corpus_.rate)
    assert not ed.set_text("zz 0.1 qq 0.2", source="phones")  # unknown phones: said, not raised
    assert "does not occur" in ed.readout.text()
    assert ed.targets.labels == ["m", "aa", "p"]  # the last good targets stay


def test_exports_round_trip(win, qtbot, tmp_path, app_manifold):
    from app.models.trajectories import export_trajectory, lip_frames, synthesize_targets, trajectory_table
    from engine.io.readers.meshfile import read_obj
    from engine.phonetics import targets as T

    m, s = app_manifold, win.state
    u = m.corpus_.utterances[0]
    s.set_utterance(u.id)
    data, _ = synthesize_targets(m, T.targets_from_utterance(m, u.id, on_collision="merge"), "manifold")
    s.set_trajectories(synthetic=data)
    traj = win.current_trajectory()
    assert traj is s.synthetic
    values, cols = trajectory_table(traj)
    export_trajectory(m, traj, tmp_path / "t.csv")
    back = np.loadtxt(tmp_path / "t.csv", delimiter=",", skiprows=1)
    header = (tmp_path / "t.csv").read_text().splitlines()[0].split(",")
    assert header == ["time", *cols]
    np.testing.assert_allclose(back[:, 1:], values, rtol=1e-5, atol=1e-6)
    np.testing.assert_allclose(back[:, 0], np.arange(len(traj)) / traj.rate, atol=1e-6)
    export_trajectory(m, traj, tmp_path / "t.npy")
    np.testing.assert_array_equal(np.load(tmp_path / "t.npy"), values)
    files = export_trajectory(m, traj, tmp_path / "seq.obj")
    assert len(files) == len(traj)
    V, F = read_obj(files[3])
    np.testing.assert_allclose(V, _points(m, lip_frames(m, traj)[3]), atol=1e-5)
    from engine.files.staging import OutputExistsError

    before = files[0].read_bytes()  # the dialog asked about seq.obj, never about the frame files in seq/
    with pytest.raises(OutputExistsError, match=r"seq_00000.obj and \d+ other files already exist; nothing was "
                                                r"written. Choose another name") as e:
        export_trajectory(m, traj, tmp_path / "seq.obj")
    assert "--force" not in str(e.value) and files[0].read_bytes() == before
    with pytest.raises(ValueError, match="cannot export"):
        export_trajectory(m, traj, tmp_path / "t.txt")
    # the 3-D views as figures
    png = win.export_view("manifold", tmp_path / "view.png")
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    from app.figures import vector_export_available

    if vector_export_available():
        svg = win.export_view("lips", tmp_path / "lips.svg")
        assert b"<svg" in svg.read_bytes()[:2000]
    # session: save, disturb, reopen -> same selection, colour mode and camera
    s.set_hemisphere("past")
    s.select_frame(400)
    s.set_color_mode("class")
    cam = win.manifold_view.camera()
    path = win.save_session(tmp_path / "view.lipspace.json")
    s.set_manifold(m, source={"path": None, "preset": "small"})
    win.manifold_view.plotter.camera.azimuth = 40
    assert win.open_session(path) is None  # same source: applied at once
    assert (s.frame, s.color_mode, s.hemisphere, s.utterance) == (400, "class", "past", u.id)
    np.testing.assert_allclose(win.manifold_view.camera(), cam, atol=1e-6)
    assert win.manifold_view.color_box.currentData() == "class"


def test_scree_panel_and_component_deformation(win, app_manifold):
    from PySide6 import QtWidgets

    from app.models.scree import scree_series

    m, s, sc = app_manifold, win.state, win.scree
    win.docks["scree"].raise_()  # its tab, behind the clusters table: the plot is made when first raised
    QtWidgets.QApplication.processEvents()
    lines = sc.figure.axes[0].get_lines()
    d = scree_series(m)
    np.testing.assert_allclose(lines[1].get_ydata(), 100 * (1 - d["y_cum"]))
    sc.spin.setValue(2)
    sc.show_box.setChecked(True)
    assert s.component == 1
    np.testing.assert_allclose(win.lip_view.main.points, _points(m, m.shape_.component_deformation(1, -2.0)),
                               atol=1e-4)
    np.testing.assert_allclose(win.lip_view.second.points, _points(m, m.shape_.component_deformation(1, 2.0)),
                               atol=1e-4)
    assert "component 2" in win.lip_view.caption.text()
    win.docks["clusters"].raise_()  # as the window starts
    QtWidgets.QApplication.processEvents()


def test_worker_reports_progress_cancels_and_fails(qapp, qtbot):
    from app.workers import TaskRunner, run_blocking
    from engine.progress import Cancelled

    seen = []

    def slow(progress):
        for k in range(10 ** 6):
            progress("step", k, 10 ** 6)
            if k == 3:
                seen.append("running")
            import time

            time.sleep(0.002)
        return "never"

    r = TaskRunner(slow, dialog=False).start()
    r.worker.progress.connect(lambda st, d, t: seen.append(d))
    qtbot.waitUntil(lambda: "running" in seen, timeout=5000)
    r.cancel()
    assert r.wait(10000) and r.state == "cancelled"
    r2 = TaskRunner(lambda p: 1 / 0, dialog=False).start()
    assert r2.wait(10000) and r2.state == "failed" and "ZeroDivisionError" in r2.error[0]
    assert run_blocking(lambda p: (p("x", 1, 1), 42)[1]) == 42
    with pytest.raises(Cancelled):
        run_blocking(lambda p: (_ for _ in ()).throw(Cancelled("stop")))


def test_audio_is_guarded(qapp, tmp_path):
    from app.audio import AudioPlayer, resolve_audio_path

    a = AudioPlayer()
    assert a.available or a.reason  # either it plays, or it says why not
    assert a.play(None) is False
    a.stop()
    wav = tmp_path / "u.wav"
    wav.write_bytes(b"RIFF")
    assert resolve_audio_path("u.wav", tmp_path / "corpus.npz") == wav
    assert resolve_audio_path("missing.wav", tmp_path / "corpus.npz") is None
    assert resolve_audio_path(None) is None


def test_audio_device_is_looked_for_on_first_use():
    """Building the window's player touches no sound device (QtMultimedia stays unimported); stopping or
    asking the position of a player never used does nothing; the first question about sound sets it up."""
    script = textwrap.dedent("""
        import sys
        from PySide6 import QtWidgets
        app = QtWidgets.QApplication([])
        from app.audio import AudioPlayer
        a = AudioPlayer()
        a.stop(); a.set_rate(2.0)
        before = ("PySide6.QtMultimedia" in sys.modules, a.position_s())
        ok = a.available or bool(a.reason)
        print("RESULT", before, ok, "PySide6.QtMultimedia" in sys.modules or "cannot load" in a.reason)
    """)
    env = dict(os.environ, QT_QPA_PLATFORM="offscreen")
    r = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, env=env, timeout=120,
                       cwd=str(Path(__file__).resolve().parents[2]))
    assert r.returncode == 0, r.stderr
    assert "RESULT (False, None) True True" in r.stdout, r.stdout + r.stderr


def test_clusters_panel_shows_ellipsoids_and_exports_table(win, tmp_path, app_manifold):
    import csv

    from PySide6 import QtCore

    panel, view, s = win.clusters, win.manifold_view, win.state
    rows = panel.table_rows()
    assert rows and panel.table.rowCount() == len(rows)
    counts = [r["count"] for r in rows]
    assert counts == sorted(counts, reverse=True)
    ph = rows[0]["phone"]
    item = next(panel.table.item(i, 0) for i in range(panel.table.rowCount()) if panel.table.item(i, 0).text() == ph)
    item.setCheckState(QtCore.Qt.CheckState.Checked)  # the user ticks the phone
    assert s.visible_phones == {ph}
    e = view.ellipsoids[ph]
    verts, _faces = s.clusters.ellipsoid(ph)
    assert e.visible and e.mesh.n_points == len(verts)
    np.testing.assert_allclose(e.mesh.points.mean(0), np.asarray(verts).mean(0), rtol=1e-4, atol=1e-4)
    panel.none_btn.click()
    assert not e.visible and item.checkState() == QtCore.Qt.CheckState.Unchecked
    out = win.export_clusters(tmp_path / "clusters.csv")
    with open(out, newline="") as fh:
        back = list(csv.DictReader(fh))
    assert [r["phone"] for r in back] == [r["phone"] for r in rows]
    assert [int(r["count"]) for r in back] == counts


def test_ticking_a_phone_redraws_no_swatch_and_each_shows_the_session_colour(win, monkeypatch):
    """Each new icon makes the table re-measure its columns (~3 ms a row): a toggle that set every row's
    icon cost 120 ms. A swatch is its label's one palette colour, ticked or not, so a toggle sets none."""
    from PySide6 import QtCore

    import app.views.clusters_panel as cp

    panel, s = win.clusters, win.state
    made = []
    real = cp._swatch
    monkeypatch.setattr(cp, "_swatch", lambda rgb: (made.append(tuple(rgb)), real(rgb))[1])
    items = {panel.table.item(i, 0).text(): panel.table.item(i, 0) for i in range(panel.table.rowCount())}
    a, b = [r["phone"] for r in panel.rows[:2]]
    items[a].setCheckState(QtCore.Qt.CheckState.Checked)
    items[b].setCheckState(QtCore.Qt.CheckState.Checked)
    assert s.visible_phones == {a, b} and made == []
    panel.none_btn.click()
    assert made == []
    shown = {ph: it.data(cp._SWATCH_ROLE) for ph, it in items.items()}
    assert shown == {ph: cp.QtGui.QColor.fromRgbF(*s.palette.colour("phone", ph)).name() for ph in shown}
    assert all(it.checkState() == QtCore.Qt.CheckState.Unchecked for it in items.values())


def test_a_large_cluster_s_members_are_flat_dots(win, monkeypatch):
    """Members shaded as spheres cost 50-70 ms of a render at 12,759 points in software GL: above the
    view's sphere limit they are drawn as flat dots, as the cloud is."""
    view, s = win.manifold_view, win.state
    a, b = [r["phone"] for r in win.clusters.rows if r["phone"] not in view.members][:2]  # never shown yet
    s.set_visible_phones({a})
    assert view.members[a].actor.prop.render_points_as_spheres  # a few hundred members: spheres
    n_b = len(s.clusters.members(b))
    monkeypatch.setattr(view, "SPHERE_POINTS_MAX", n_b - 1)
    s.set_visible_phones({a, b})
    assert view.members[b].mesh.n_points == n_b and not view.members[b].actor.prop.render_points_as_spheres
    s.set_visible_phones(())


def test_worker_shows_engine_warnings_in_the_status_bar(win, qtbot):
    import warnings

    from app.workers import run_task
    from engine.graph.states import StateGraphConnectivityWarning

    def task(progress):
        progress("fitting", 1, 1)
        warnings.warn("the state graph is not strongly connected: 2 components", StateGraphConnectivityWarning,
                      stacklevel=1)
        return 7

    runner = run_task(task, parent=win, dialog=False)
    qtbot.waitUntil(lambda: runner.state != "running", timeout=10000)
    assert runner.state == "done" and runner.result == 7  # a warning about the data never fails the task
    assert runner.warnings == ["the state graph is not strongly connected: 2 components"]
    assert "not strongly connected" in win.statusBar().currentMessage()


def test_open_runs_in_a_worker_with_status_bar_progress_and_cancel(win, qtbot, tmp_path, app_manifold):
    from PySide6 import QtWidgets

    from app.models.task_status import stage_text
    from app.views.task_progress import TaskProgress

    corpus = tmp_path / "c.npz"
    app_manifold.corpus_.save(corpus)
    before = win.state.manifold
    runner = win.open_source(corpus)  # File > Open of a corpus: fitted in the worker
    prog = win.findChild(TaskProgress, "task_progress")
    try:
        assert runner.dialog is None and prog.isVisible() and prog.runner is runner
        assert QtWidgets.QApplication.activeModalWidget() is None  # nothing blocks the window
        qtbot.waitUntil(lambda: len(prog.stages) >= 2 or runner.state != "running", timeout=30000)
        assert runner.state == "running"
        # the window answers while the worker runs
        win.state.set_color_mode("class")
        assert win.manifold_view.color_box.currentData() == "class"
        # a stage without a total, or whose count is complete, is busy, never a bar stuck at 100 %
        runner.worker.progress.emit("embedding", 4, 0)
        assert prog.bar.maximum() == 0 and prog.label.text().startswith("embedding · ")
        runner.worker.progress.emit("tangent frames", 1, 1)
        assert prog.bar.maximum() == 0
        runner.worker.progress.emit("shape space", 2, 9)
        assert (prog.bar.maximum(), prog.bar.value()) == (9, 2) and "shape space 2/9" in prog.label.text()
        runner.worker.progress.emit("shape space", 3, 9)                 # a count made: the time left is said
        assert "shape space 3/9" in prog.label.text() and " left" in prog.label.text()
        prog.cancel_btn.click()
        qtbot.waitUntil(lambda: runner.state != "running", timeout=30000)
    finally:
        runner.cancel()
    assert runner.state == "cancelled" and win.state.manifold is before
    assert not prog.isVisible() and prog.runner is None
    assert stage_text("embedding", 3, 10, 4.2) == "embedding 3/10 · 4 s"


def test_open_session_reloads_its_source_in_the_worker(win, qtbot, tmp_path, app_manifold):
    """Last test: it replaces the window's manifold by a loaded copy."""
    import json

    mfile = app_manifold.save(tmp_path / "m.npz")
    sess = tmp_path / "s.lipspace.json"
    sess.write_text(json.dumps({"lipspace_session": 1, "source": {"path": str(mfile), "preset": "default"},
                                "selection": {"frame": 50, "state": None, "target": None},
                                "color_mode": "class", "hemisphere": "past"}))
    runner = win.open_session(sess)
    assert runner is not None  # another source: loaded in the worker, then the session applied
    qtbot.waitUntil(lambda: runner.state != "running", timeout=30000)
    s = win.state
    assert runner.state == "done" and s.source["path"] == str(mfile.resolve())
    assert (s.frame, s.color_mode, s.hemisphere) == (50, "class", "past")
    assert "m.npz" in win.windowTitle()
    np.testing.assert_array_equal(s.manifold.Fy_, app_manifold.Fy_)
