"""The window's views of conditions and signals: the Compare panel (background run, cancel, sortable table, rows
selecting), small multiples (one view per level, one camera), the gesture tier (drag, delete, undo) and the channels
under the timeline, the landmarks marked on the manifold (needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import numpy as np
import pytest
from PySide6 import QtCore
from PySide6.QtTest import QTest

from engine.recordings.signals.gestures import LANDMARKS

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def win(qapp, field_manifold, main_window_factory):
    with main_window_factory(qapp, field_manifold, size=(1500, 1000)) as w:
        yield w


def _settle(qapp, n=10):
    for _ in range(n):
        qapp.processEvents()


def _choose(box, data):
    k = box.findData(data)
    assert k >= 0, data
    box.setCurrentIndex(k)


def test_compare_panel_refuses_a_bad_request_at_once(win):
    p = win.compare_panel
    _choose(p.field_box, "condition")
    assert p.levels_edit.text() == ", ".join(sorted(["a", "b", "c"]))  # a few levels: all suggested
    p.levels_edit.setText("a, z")
    assert p.run() is False and p.runner is None
    assert "'z'" in p.status.text() and "condition" in p.status.text()


def test_compare_panel_runs_in_the_background_and_its_rows_select(win, qapp):
    p, s = win.compare_panel, win.state
    _choose(p.field_box, "condition")
    _choose(p.pair_box, "text")
    p.levels_edit.setText("a, b, c")
    p.perm_spin.setValue(99)
    assert p.run() is True and p.cancel_btn.isEnabled() and not p.run_btn.isEnabled()
    assert p.runner.wait(120_000)
    _settle(qapp)
    shown = s.comparison
    assert shown is not None and shown.request.paired_by == "text" and shown.request.n_permutations == 99
    assert p.model.rowCount() == len(shown.result.rows_) and not p.cancel_btn.isEnabled()
    assert [p.contrast_box.itemText(k) for k in range(p.contrast_box.count())] == ["b against a", "c against a"]
    q = p.model.cols.index("q")
    p.table.sortByColumn(q, QtCore.Qt.SortOrder.AscendingOrder)
    qs = np.array([r["q"] for r in p.model.rows], float)
    finite = qs[np.isfinite(qs)]
    assert np.all(np.diff(finite) >= 0) and np.all(np.isfinite(qs[:len(finite)]))  # missing last
    _choose(p.family_box, "state")
    assert p.model.rowCount() > 0 and {r["family"] for r in p.model.rows} == {"state"}
    p.table.selectRow(0)
    _settle(qapp)
    row = p.model.row(0)
    assert s.state == int(row["target"]) and s.color_mode == "difference"
    assert s.comparison.levels == (row["level_a"], row["level_b"])
    p.contrast_box.setCurrentIndex(1)
    assert s.comparison.contrast == 1


def test_a_comparison_can_be_cancelled(win, qapp):
    p, s = win.compare_panel, win.state
    before = s.comparison
    _choose(p.field_box, "condition")
    p.levels_edit.setText("a, b")
    p.perm_spin.setValue(99999)
    assert p.run()
    p.cancel()
    assert p.runner.wait(120_000)
    _settle(qapp)
    assert p.runner.state == "cancelled" and s.comparison is before
    assert p.status.text().startswith("cancelled") and p.run_btn.isEnabled()


def test_small_multiples_show_one_view_per_level_through_one_camera(win, qapp):
    s, sm = win.state, win.small_multiples
    s.set_color_field(None)  # no field: the dock says how to choose one instead of an empty 3-D view
    win.show_compare()
    _settle(qapp, 20)
    assert sm.field is None and sm.placeholder.isVisible() and not sm.plotter.interactor.isVisible()
    assert "Colour › Field" in sm.placeholder.text()
    with s.batch():
        s.colour_by_field("condition")
        s.set_field_filter(())
    _settle(qapp, 20)
    assert sm.isVisible() and sm.field == "condition" and sorted(sm.levels) == ["a", "b", "c"]
    assert sm.plotter.interactor.isVisible() and not sm.placeholder.isVisible() and "condition: " in sm.caption.text()
    values = s.manifold.corpus_.utterance_index
    fields = {u: dict(x.fields)["condition"] for u, x in enumerate(s.manifold.corpus_.utterances)}
    for lv, f in zip(sm.levels, sm.frames):
        assert len(f) > 0 and {fields[int(u)] for u in np.unique(values[f])} == {lv}
    cam = win.manifold_view.plotter.renderer.GetActiveCamera()
    assert all(sm.plotter.renderers[k].GetActiveCamera() is cam for k in range(len(sm.levels)))
    moves = win.camera_link.n_moves
    cam.Azimuth(20.0)
    assert win.camera_link.n_moves == moves + 1
    s.select_frame(int(sm.frames[1][0]))
    _settle(qapp)
    for view in sm.views:  # the selection is marked in every view
        assert view["marker"].visible
    # the hemisphere within the horizon, coloured in every view as in the main one
    from app.models.colouring import point_colors
    from app.scene.manifold import to_rgb8

    with s.batch():
        s.select_state(int(s.manifold.states_.labels_[sm.frames[0][0]]))
        s.set_color_mode("distance")
        s.set_horizon(50.0)
    _settle(qapp)
    c = point_colors("distance", s.manifold, s)
    for view, f in zip(sm.views, sm.frames):
        np.testing.assert_array_equal(view["points"].rgb, to_rgb8(c.rgb[s.cloud.group_of[f]]))
    s.set_horizon(150.0)
    _settle(qapp)
    assert not np.array_equal(to_rgb8(point_colors("distance", s.manifold, s).rgb), to_rgb8(c.rgb))
    c = point_colors("distance", s.manifold, s)
    np.testing.assert_array_equal(sm.views[0]["points"].rgb, to_rgb8(c.rgb[s.cloud.group_of[sm.frames[0]]]))
    s.set_field_levels("condition", ["a", "c"])
    _settle(qapp, 20)
    assert sm.levels == [lv for lv in sm.levels if lv in ("a", "c")] and len(sm.levels) == 2
    s.set_field_filter(())


def _load_utterance(win, qapp):
    ed = win.editor
    ed.utt_box.setCurrentIndex(1)
    assert ed.load()
    if ed._finder is not None:
        assert ed._finder.wait(60_000)
    _settle(qapp)
    return ed


def test_the_gesture_tier_drags_and_deletes_landmarks_undoably(win, qapp):
    ed = _load_utterance(win, qapp)
    s, tier = win.state, ed.gesture_tier
    uid = s.utterance
    assert tier.isVisible() and ed.channels.isVisible() and ed.channels.names == ["lip_aperture"]
    gs = s.gestures
    assert gs is not None and gs is ed.signals.gestures
    own = [g for g in gs.of_utterance(uid).tolist() if np.all(np.isfinite(gs.times[g]))]
    assert own
    ed.set_zoom(4.0)  # room to drag
    _settle(qapp)
    j = LANDMARKS.index("MAXC")
    g = max(own, key=lambda k: np.ptp(ed.signals.editor.bounds(k, j)))
    lo, hi = ed.signals.editor.bounds(g, j)
    t0 = float(gs.times[g, j])
    x0 = int(round(tier.point_x(g, j)))
    target = min(hi, t0 + 0.5 * (hi - t0)) if hi > t0 else max(lo, t0 - 0.5 * (t0 - lo))
    x1 = int(round(tier.time_x(target)))
    assert abs(x1 - x0) >= 2
    y = tier.height() // 2
    QTest.mousePress(tier, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                     QtCore.QPoint(x0, y))
    assert tier.chosen == (g, j)
    QTest.mouseMove(tier, QtCore.QPoint(x1, y))
    QTest.mouseRelease(tier, QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier,
                       QtCore.QPoint(x1, y))
    _settle(qapp)
    moved = float(s.gestures.times[g, j])
    assert moved != t0 and lo <= moved <= hi and abs(moved - target) < 2.0 / ed.signals.corpus.rate
    assert s.gestures is ed.signals.gestures  # the state follows every edit (the manifold's marks)
    win.undo_action.trigger()
    _settle(qapp)
    assert float(s.gestures.times[g, j]) == t0
    win.redo_action.trigger()
    assert float(s.gestures.times[g, j]) == moved
    tier.choose((g, j))
    QTest.keyClick(tier, QtCore.Qt.Key.Key_Delete)
    assert np.isnan(s.gestures.times[g, j])
    win.undo_action.trigger()
    assert float(s.gestures.times[g, j]) == moved


def test_the_landmarks_are_marked_on_the_manifold(win, qapp):
    _load_utterance(win, qapp)
    s, view = win.state, win.manifold_view
    _settle(qapp)
    gs = s.gestures
    f = gs.frames(s.manifold.corpus_.bounds)[gs.of_utterance(s.utterance)]
    want = np.asarray(s.manifold.Fy_[f[f >= 0]])[:, :3]
    h = view.handles["landmarks"]
    assert h.visible and h.points.shape == want.shape
    np.testing.assert_allclose(h.points, want, atol=1e-5)
    assert [code for code, _rgb in view.landmark_rows()] == [n for n in LANDMARKS
                                                              if n in {LANDMARKS[j] for j in np.nonzero(f >= 0)[1]}]


def test_channels_chosen_in_the_signals_menu_stack_under_the_timeline(win, qapp):
    ed = _load_utterance(win, qapp)
    ed.toggle_channel("lip_protrusion", True)
    _settle(qapp)
    assert ed.channels.names == ["lip_aperture", "lip_protrusion"]
    assert ed.channels.height() == 2 * ed.channels.row_h
    v = ed.signals.panel.view(win.state.utterance)
    assert len(v.channels[1].values) == len(v.times) == ed.targets.n_frames
    assert "lip_protrusion at" in ed.channels.readout(QtCore.QPointF(ed.channels.frame_x(3), 1.5 * ed.channels.row_h))
    settings = win.session_extra()["signals"]
    assert settings["channels"] == ["lip_aperture", "lip_protrusion"]
    ed.toggle_channel("lip_protrusion", False)
    assert ed.signals.panel.channels == ("lip_aperture",)


def test_typed_text_says_once_that_channels_are_of_an_utterance(win, qapp):
    """Typed text has no utterance: the channels' strip says why it is empty, and the gesture tier, which
    would say the same, is hidden (both said it, one above the other)."""
    ed = _load_utterance(win, qapp)
    assert ed.gesture_tier.isVisible() and ed.channels.names == ["lip_aperture"]
    try:
        assert ed.set_text("bob meets mum", source="text")
        _settle(qapp)
        assert ed.targets.utterance is None
        assert ed.channels.isVisible() and ed.channels.message.startswith("no utterance")
        assert ed.gesture_tier.isHidden()
        shown = [w for w in (ed.channels, ed.gesture_tier) if w.isVisible() and w.message.startswith("no utterance")]
        assert shown == [ed.channels]
        ed.toggle_channel("lip_aperture", False)  # no channel chosen: the gesture tier says it instead
        _settle(qapp)
        assert not ed.channels.isVisible()
        assert ed.gesture_tier.isVisible() and ed.gesture_tier.message.startswith("no utterance")
    finally:
        ed.toggle_channel("lip_aperture", True)
        ed.set_source("utterance")
        _load_utterance(win, qapp)


def test_a_session_keeps_the_channels_and_the_edited_landmarks(win, qapp):
    ed = _load_utterance(win, qapp)
    gs = win.state.gestures
    g = int(np.flatnonzero(np.all(np.isfinite(gs.times), axis=1))[0])
    j = LANDMARKS.index("NONS")
    lo, hi = ed.signals.editor.bounds(g, j)
    ed.move_landmark(g, j, 0.5 * (lo + hi))
    ed.toggle_channel("lip_protrusion", True)
    extra = win.session_extra()
    edited = win.state.gestures.times.copy()
    ed.apply_signals_settings(extra["signals"])  # as a session opened on this corpus restores them
    assert ed._finder.wait(60_000)
    _settle(qapp)
    assert ed.signals.panel.channels == ("lip_aperture", "lip_protrusion") and ed.signals.edited
    np.testing.assert_allclose(win.state.gestures.times, edited, atol=1e-6, equal_nan=True)
    assert not ed.gesture_undo_stack.canUndo()  # a session's edits start a new history
    assert win.compare_panel.settings()["field"] == extra["compare"]["field"]
    ed.toggle_channel("lip_protrusion", False)


def test_the_colour_box_and_the_filter_menu_write_the_state(win, qapp):
    s, view = win.state, win.manifold_view
    with s.batch():
        s.set_field_filter(())
        s.set_color_mode("density")
    box = view.color_box
    items = [box.itemText(k) for k in range(box.count())]
    assert {"Field: condition", "Field: text", "Field: repetition", "Difference"} <= set(items)
    box.setCurrentIndex(box.findData("field:condition"))
    assert (s.color_mode, s.color_field) == ("field", "condition")
    win.undo_action.trigger()  # choosing a field is one action, undone as one
    assert s.color_mode == "density" and box.currentData() == "density"
    view._fill_filter_menu()
    subs = {a.text(): a.menu() for a in view.filter_menu.actions() if a.menu() is not None}
    cond = subs["condition (3 levels)"]
    b = next(a for a in cond.actions() if a.text() == "b")
    b.setChecked(True)
    assert s.field_filter == {("condition", "b")} and view.filter_btn.text() == "Filter (1)"
    s.set_field_filter(())
    assert view.filter_btn.text() == "Filter"
