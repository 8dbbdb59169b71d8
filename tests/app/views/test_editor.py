"""The trajectory editor: undo/redo of every target edit, targets kept in their phone, ms ticks, zoom,
the full warning list and keyboard playback (needs a display: Xvfb is started if absent)."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.target_editing import move_target, phone_frames, remove_target, target_bounds, time_ticks

PHONES = "m 0.2 aa 0.3 p 0.2"


# ------------------------------------------------------------------ Qt-free edits
def _targets(app_manifold):
    from engine.phonetics.targets import targets_from_phones

    return targets_from_phones(app_manifold, PHONES)


def test_a_moved_target_stays_inside_its_phone_interval(app_manifold):
    tg = _targets(app_manifold)
    aa = tg.phones[1]
    lo, hi = phone_frames(aa, tg.rate, tg.n_frames)
    assert tg.targets[1].label == tg.phones[1].label and lo <= tg.targets[1].frame <= hi
    assert target_bounds(tg, 1) == (lo, hi)  # the phone is narrower than the gap to the neighbours
    assert move_target(tg, 1, 10_000).targets[1].frame == hi  # dragged far right: stops at the phone's end
    assert move_target(tg, 1, -5).targets[1].frame == lo
    assert move_target(tg, 1, lo + 2).targets[1].frame == lo + 2
    # the first target cannot leave /m/ either, though nothing is before it
    assert move_target(tg, 0, 10_000).targets[0].frame == phone_frames(tg.phones[0], tg.rate, tg.n_frames)[1]


def test_remove_target_refuses_the_last_one(app_manifold):
    tg = _targets(app_manifold)
    one = remove_target(remove_target(tg, 2), 0)
    assert [t.label for t in one.targets] == [tg.targets[1].label]
    with pytest.raises(ValueError, match="last target"):
        remove_target(one, 0)


def test_time_ticks_are_whole_milliseconds_spaced_for_the_width():
    step, ticks = time_ticks(0, 700, 600)
    assert step == 100 and ticks == [0, 100, 200, 300, 400, 500, 600, 700]
    step2, ticks2 = time_ticks(0, 700, 4800)  # zoomed in 8x: finer ticks, still >= 56 px apart
    assert step2 < step and step2 * 4800 / 700 >= 56 and ticks2[1] - ticks2[0] == step2
    assert time_ticks(0, 0, 600) == (time_ticks(0, 0, 600)[0], [])


# ------------------------------------------------------------------ the widget

@pytest.fixture(scope="module")
def shared_window(qapp, app_manifold, main_window_factory):
    with main_window_factory(qapp, app_manifold) as w:
        yield w


@pytest.fixture
def editor_window(fresh_window):
    """The shared window, reset for each test (conftest's ``fresh_window``)."""
    return fresh_window


@pytest.fixture
def ed(editor_window, qapp):
    e = editor_window.editor
    assert e.set_text(PHONES, source="phones")
    e.set_zoom(1.0)
    qapp.processEvents()
    return e


def _drag(qtbot, tl, index, dx):
    from PySide6 import QtCore

    start = QtCore.QPoint(int(tl.marker_x(index)), int(tl.marker_y()))
    qtbot.mousePress(tl, QtCore.Qt.MouseButton.LeftButton, pos=start)
    qtbot.mouseMove(tl, start + QtCore.QPoint(dx, 0))
    qtbot.mouseRelease(tl, QtCore.Qt.MouseButton.LeftButton, pos=start + QtCore.QPoint(dx, 0))


@pytest.mark.gui
def test_every_target_edit_undoes_and_redoes_from_the_edit_menu(ed, editor_window, qtbot, app_manifold):
    win = editor_window
    loaded = ed.targets
    frames0 = list(loaded.frames)
    assert win.undo_action.shortcut().toString() == "Ctrl+Z"
    assert "Ctrl+Shift+Z" in [k.toString() for k in win.redo_action.shortcuts()]
    assert win.undo_action in win.menuBar().actions()[1].menu().actions()  # Edit menu
    assert not win.undo_action.isEnabled()

    _drag(qtbot, ed.timeline, 1, 60)  # move
    moved = list(ed.targets.frames)
    assert moved[1] > frames0[1] and ed.undo_stack.count() == 1 and win.undo_action.isEnabled()
    ed.timeline.select(0)
    assert ed.remove_selected()  # remove
    assert len(ed.targets.targets) == 2
    win.editor.state.select_state(3)
    assert ed.add_selected_state()  # add a clicked state
    assert any(t.state == 3 and t.label == "" for t in ed.targets.targets)
    assert ed.reset_targets()  # reset
    assert list(ed.targets.frames) == frames0 and ed.undo_stack.count() == 4

    win.undo_action.trigger()  # undo reset -> the added state is back
    assert any(t.state == 3 for t in ed.targets.targets)
    win.undo_action.trigger()  # undo add
    assert not any(t.state == 3 for t in ed.targets.targets) and len(ed.targets.targets) == 2
    win.undo_action.trigger()  # undo remove
    assert list(ed.targets.frames) == moved
    win.undo_action.trigger()  # undo move
    assert list(ed.targets.frames) == frames0 and ed.timeline.targets is ed.targets
    assert not win.undo_action.isEnabled()
    for _ in range(2):
        win.redo_action.trigger()
    assert len(ed.targets.targets) == 2 and ed.targets.frames[0] == moved[1]
    assert "undone" not in ed.readout.text()


@pytest.mark.gui
def test_loading_new_targets_starts_a_new_history(ed, qtbot):
    _drag(qtbot, ed.timeline, 1, 40)
    assert ed.undo_stack.count() == 1
    assert ed.set_text("b 0.2 iy 0.2", source="phones")
    assert ed.undo_stack.count() == 0 and not ed.reset_btn.isEnabled()


@pytest.mark.gui
def test_dragging_far_keeps_the_target_in_its_phone(ed, qtbot):
    tg = ed.targets
    lo, hi = phone_frames(tg.phones[1], tg.rate, tg.n_frames)
    _drag(qtbot, ed.timeline, 1, 2000)
    assert ed.targets.targets[1].frame == hi < ed.targets.targets[2].frame


@pytest.mark.gui
def test_zoom_widens_the_timeline_and_refines_the_ms_ticks(ed, qtbot, qapp):
    from PySide6 import QtCore, QtGui, QtWidgets

    view_w = ed.scroll.viewport().width()
    assert abs(ed.timeline.width() - view_w) <= 1
    step1, ticks1 = ed.timeline.ticks()
    assert ticks1[0] == 0 and all(t % step1 == 0 for t in ticks1)
    ed.zoom_in_btn.click()
    ed.zoom_in_btn.click()
    assert ed.zoom == pytest.approx(1.5625)
    assert ed.timeline.width() == pytest.approx(view_w * 1.5625, abs=1)
    # the mouse wheel over the timeline zooms too, keeping the time under the mouse in place
    x = ed.timeline.width() * 0.75
    bar = ed.scroll.horizontalScrollBar()
    t_before = ed.timeline.frame_at(x)
    on_screen = x - bar.value()
    ev = QtGui.QWheelEvent(QtCore.QPointF(x, 40), QtCore.QPointF(x, 40), QtCore.QPoint(0, 0), QtCore.QPoint(0, 360),
                           QtCore.Qt.MouseButton.NoButton, QtCore.Qt.KeyboardModifier.NoModifier,
                           QtCore.Qt.ScrollPhase.NoScrollPhase, False)
    QtWidgets.QApplication.sendEvent(ed.timeline, ev)
    assert ed.zoom == pytest.approx(1.5625 * 1.25 ** 3)
    x_after = ed.timeline._x(t_before)
    assert x_after - bar.value() == pytest.approx(on_screen, abs=2)
    step2, _ = ed.timeline.ticks()
    assert step2 < step1
    ed.fit_btn.click()
    assert ed.zoom == 1.0 and abs(ed.timeline.width() - view_w) <= 1
    ed.set_zoom(1e6)
    assert ed.zoom == 64.0


@pytest.mark.gui
def test_every_synthesis_warning_is_listed(ed, qtbot, editor_window):
    # the paper's path (viterbi) undershoots targets it cannot reach in time and warns for each:
    # six phones of one frame each leave it no time between them
    assert ed.set_text("m 0.017 iy 0.017 p 0.017 aa 0.017 b 0.017 uw 0.017", source="phones")
    ed.set_method("viterbi")
    runner = ed.synthesize()
    qtbot.waitUntil(lambda: runner.state != "running", timeout=60000)
    syn = editor_window.state.synthetic
    warns = syn.extra["warnings"]
    assert len(warns) >= 2 and all("unreachable in time" in w for w in warns)
    items = [ed.warnings_list.item(i).text() for i in range(ed.warnings_list.count())]
    assert len(items) == len(warns) >= 2 and all(w in it for w, it in zip(warns, items))
    assert ed.warnings_list.isVisible()
    editor_window.state.set_trajectories(synthetic=None)
    assert ed.warnings_list.count() == 0 and not ed.warnings_list.isVisible()


@pytest.mark.gui
def test_a_synthesis_shows_busy_only_when_it_outlasts_the_dialog_delay(ed, qtbot, editor_window, monkeypatch):
    """A quick synthesis repaints nothing before its result; a slow one disables the button and says
    so once its dialog opens, and a second Synthesise meanwhile starts nothing."""
    import threading

    import app.views.trajectory_editor as te
    from app.workers import DIALOG_DELAY_MS

    ed.set_method("linear")
    before = ed.readout.text()
    runner = ed.synthesize()
    assert ed.synth_btn.isEnabled() and ed.readout.text() == before  # nothing painted before the result
    qtbot.waitUntil(lambda: runner.state != "running", timeout=30000)
    qtbot.wait(DIALOG_DELAY_MS + 100)
    assert runner.state == "done" and ed.synth_btn.isEnabled() and "synthesising" not in ed.readout.text()

    release, real = threading.Event(), te.synthesize_targets

    def slow(*args, **kwargs):
        release.wait(20)
        return real(*args, **kwargs)

    monkeypatch.setattr(te, "synthesize_targets", slow)
    try:
        runner = ed.synthesize()
        assert ed.synthesize() is runner  # one at a time
        qtbot.waitUntil(lambda: not ed.synth_btn.isEnabled(), timeout=DIALOG_DELAY_MS + 5000)
        assert ed.readout.text() == "synthesising with linear…" and runner.state == "running"
    finally:
        release.set()
    qtbot.waitUntil(lambda: runner.state != "running", timeout=30000)
    assert runner.state == "done" and ed.synth_btn.isEnabled() and "synthesising" not in ed.readout.text()


@pytest.mark.gui
def test_space_plays_and_arrows_step_through_the_state(ed, qtbot, editor_window):
    from PySide6 import QtCore

    s = editor_window.state
    uid = s.manifold.corpus_.utterances[0].id
    s.set_utterance(uid)
    assert s.n_playback > 3
    ed.timeline.setFocus()
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Right)
    assert s.playback == 0 and not s.playing  # from the selection to the first frame
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Right)
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Right)
    assert s.playback == 2
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Left)
    assert s.playback == 1
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Space)
    assert s.playing
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Space)
    assert not s.playing
    s.set_playback(s.n_playback - 1)
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Right)
    assert s.playback == s.n_playback - 1  # the last frame is the end


@pytest.mark.gui
def test_delete_and_plus_minus_keys_in_the_timeline(ed, qtbot, editor_window):
    from PySide6 import QtCore

    n = len(ed.targets.targets)
    ed.timeline.setFocus()
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Delete)  # nothing chosen: nothing removed, and it says why
    assert len(ed.targets.targets) == n and "choose a target" in ed.readout.text()
    ed.timeline.select(2)
    assert ed.remove_btn.isEnabled()
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Delete)
    assert len(ed.targets.targets) == n - 1 and ed.timeline.selected is None
    editor_window.undo_action.trigger()
    assert len(ed.targets.targets) == n
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Plus)
    assert ed.zoom == pytest.approx(1.25)
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Minus)
    assert ed.zoom == pytest.approx(1.0)


@pytest.mark.gui
def test_default_method_is_the_one_best_on_this_corpus_validation_and_is_named(ed, qtbot, editor_window,
                                                                                app_manifold):
    """The editor opens on "Best on validation": phone input gets the method the corpus's own validation split
    measured best in the phones protocol, a corpus utterance (its states and X) the oracle protocol's best, and
    the readout names it with its validation figure."""
    from engine.synthesis.method_choice import choose_methods

    assert ed.method_box.itemData(0) == "best"  # the first entry, what a new editor shows
    ed.set_method("best")  # (an earlier test of this window chose another)
    choice = choose_methods(app_manifold)  # what the synthesis below reads from the cache (or measures)
    for source, text, protocol in (("phones", PHONES, "phones"), ("utterance", None, "oracle")):
        if source == "utterance":
            ed.set_source("utterance")
            assert ed.load()
        else:
            assert ed.set_text(text, source=source)
        runner = ed.synthesize()
        qtbot.waitUntil(lambda r=runner: r.state != "running", timeout=240000)
        best = choice["best"][protocol]
        syn = editor_window.state.synthetic
        assert syn.extra["method"] == best
        assert f"method: {best}, best on validation ({protocol} protocol" in ed.readout.text()


# ------------------------------------------------------------------ a timeline that behaves like Praat's
def _at(tl, frame):
    """A point on the phone row of the timeline at ``frame``, clear of boundaries."""
    from PySide6 import QtCore

    top, h = tl._rows()["phones"]
    return QtCore.QPoint(int(round(tl._x(frame))), int(top + h // 2))


def _utterance(ed, k=0):
    ed.set_source("utterance")
    ed.utt_box.setCurrentIndex(k)
    assert ed.load()
    ed.set_zoom(1.0)


@pytest.mark.gui
def test_a_click_sets_the_cursor_and_selects_the_state_under_it(ed, qtbot, editor_window):
    from PySide6 import QtCore

    s = editor_window.state
    _utterance(ed)
    tl = ed.timeline
    k = 20
    qtbot.mouseClick(tl, QtCore.Qt.MouseButton.LeftButton, pos=_at(tl, k))
    assert abs(tl.cursor - k) <= 1 and s.playback == tl.cursor and not s.playing
    assert s.frame == int(s.original.frames[tl.cursor]) and s.state == int(s.manifold.states_.labels_[s.frame])
    assert tl.time_selection is None


@pytest.mark.gui
def test_a_drag_selects_and_tab_plays_the_selection_or_the_visible_part_and_stops(ed, qtbot, editor_window):
    from PySide6 import QtCore

    s = editor_window.state
    _utterance(ed)
    tl = ed.timeline
    qtbot.mousePress(tl, QtCore.Qt.MouseButton.LeftButton, pos=_at(tl, 10))
    qtbot.mouseMove(tl, _at(tl, 20))
    qtbot.mouseMove(tl, _at(tl, 30))
    qtbot.mouseRelease(tl, QtCore.Qt.MouseButton.LeftButton, pos=_at(tl, 30))
    a, b = tl.time_selection
    assert abs(a - 10) < 1 and abs(b - 30) < 1 and ed.sound.time_selection == tl.time_selection
    tl.setFocus()
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_Tab)                       # Tab: the selection, and stop at its end
    assert s.playing and s.playback == int(np.floor(a)) and s.play_stop == int(np.ceil(b)) + 1
    assert editor_window.focusWidget() is tl                         # Tab did not move the focus
    s.set_playback(s.play_stop + 5)                                  # the clock ran past the end
    assert not s.playing and s.playback == int(np.ceil(b))
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_Tab)
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_Tab)                        # Tab while playing stops
    assert not s.playing
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_Escape)                     # no selection: the visible part plays
    assert tl.time_selection is None
    ed.set_zoom(4.0)
    lo, hi = ed.visible_frames()
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_Tab)
    assert s.playing and s.playback == int(np.floor(lo)) and s.play_stop == int(np.ceil(hi)) + 1
    s.set_playing(False)
    ed.set_cursor_frame(12)
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_Tab, QtCore.Qt.KeyboardModifier.ShiftModifier)  # Shift+Tab: from the cursor
    assert s.playing and s.playback == 12 and s.play_stop is None
    s.set_playing(False)
    ed.set_zoom(1.0)


@pytest.mark.gui
def test_praats_zoom_keys_and_ctrl_o_opens_no_file(ed, qtbot, editor_window, monkeypatch):
    from PySide6 import QtCore, QtWidgets

    opened = []
    monkeypatch.setattr(QtWidgets.QFileDialog, "getOpenFileName", lambda *a, **k: opened.append(a) or ("", ""))
    _utterance(ed)
    tl = ed.timeline
    tl.setFocus()
    ctrl = QtCore.Qt.KeyboardModifier.ControlModifier
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_I, ctrl)
    assert ed.zoom == pytest.approx(2.0)
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_O, ctrl)
    assert ed.zoom == pytest.approx(1.0) and opened == []            # zoom out, not File › Open
    ed.set_time_selection((30.0, 45.0))
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_N, ctrl)                    # to the selection
    lo, hi = ed.visible_frames()
    assert abs(lo - 30) < 1.5 and abs(hi - 45) < 1.5
    qtbot.keyClick(tl, QtCore.Qt.Key.Key_A, ctrl)                    # all
    assert ed.zoom == pytest.approx(1.0)
    ed.set_time_selection(None)


@pytest.mark.gui
def test_space_after_synthesise_plays_and_never_synthesises_again(ed, qtbot, editor_window):
    from PySide6 import QtCore

    s = editor_window.state
    ed.set_method("linear")
    qtbot.mouseClick(ed.synth_btn, QtCore.Qt.MouseButton.LeftButton)
    qtbot.waitUntil(lambda: s.synthetic is not None, timeout=30000)
    runner = ed._runner
    assert not ed.synth_btn.hasFocus()
    editor_window.activateWindow()
    ed.timeline.setFocus()
    qtbot.keyClick(ed.timeline, QtCore.Qt.Key.Key_Space)
    assert s.playing and ed._runner is runner                        # it plays, no second synthesis
    s.set_playing(False)
    ed.method_box.setFocus()                                         # Space elsewhere in the editor plays too
    ed.key_shortcuts["Space"].activated.emit()
    assert s.playing and ed._runner is runner
    s.set_playing(False)


@pytest.mark.gui
def test_a_phone_boundary_drags_undoes_and_writes_a_textgrid(ed, qtbot, editor_window, tmp_path):
    from PySide6 import QtCore

    from app.models.tier_editing import boundary_limits

    tl = ed.timeline
    before = ed.targets
    x = tl.boundary_x("phones", 1)
    top, h = tl._rows()["phones"]
    start = QtCore.QPoint(int(round(x)), int(top + h // 2))
    assert tl.boundary_at(QtCore.QPointF(start)) == ("phones", 1)
    qtbot.mousePress(tl, QtCore.Qt.MouseButton.LeftButton, pos=start)
    qtbot.mouseMove(tl, start + QtCore.QPoint(25, 0))
    qtbot.mouseRelease(tl, QtCore.Qt.MouseButton.LeftButton, pos=start + QtCore.QPoint(25, 0))
    moved = ed.targets.phones
    assert moved[0].end > before.phones[0].end and moved[1].start == moved[0].end
    lo, hi = boundary_limits(before, (), "phones", 1)
    assert lo <= moved[0].end <= hi                                  # the /aa/ target stays in /aa/
    assert all(t.frame == u.frame for t, u in zip(ed.targets.targets, before.targets))
    editor_window.undo_action.trigger()
    assert ed.targets.phones == before.phones and tl.targets.phones == before.phones
    editor_window.redo_action.trigger()
    assert ed.targets.phones == moved
    path = ed.save_textgrid(tmp_path / "edited.TextGrid")
    text = path.read_text(encoding="utf-8")
    assert 'name = "phones"' in text and 'name = "targets"' in text and repr(float(moved[0].end)) in text


@pytest.mark.gui
def test_labels_are_elided_with_a_tooltip_and_never_struck_through(ed, qtbot, editor_window):
    assert ed.set_text("a breath of air", source="text")
    tl = ed.timeline
    assert [w.label for w in tl.words] == ["a", "breath", "of", "air"]
    assert tl.tiers_height() == tl.HEIGHT + tl.WORD_H
    k = [w.label for w in tl.words].index("breath")
    ed.scroll.viewport().resize(140, ed.scroll.viewport().height())  # a narrow timeline
    ed.set_zoom(1.0)
    shown = tl.label_shown("words", k)
    assert shown == "" or (shown.endswith("…") and "breath".startswith(shown[:-1]))   # "bre…", never "reat"
    assert "'breath'" in tl._tooltip(tl.interval_rect("words", k).center().toPoint())
    ed.scroll.viewport().resize(1200, ed.scroll.viewport().height())
    ed.set_zoom(1.0)
    img = tl.grab().toImage()
    for tier, ivs in (("words", tl.words), ("phones", tl.targets.phones)):
        for i in range(len(ivs)):
            text = tl.label_shown(tier, i)
            if not text:
                continue
            r = tl.interval_rect(tier, i)
            w = tl.fontMetrics().horizontalAdvance(text)
            ratio = img.devicePixelRatio()
            for x in range(int(r.center().x() - w / 2), int(r.center().x() + w / 2)):
                for y in range(int(r.top() + 6), int(r.bottom() - 2)):
                    c = img.pixelColor(int(x * ratio), int(y * ratio))
                    assert not (c.red() > 170 and c.green() < 60 and c.blue() < 60), (tier, ivs[i].label, x, y)
