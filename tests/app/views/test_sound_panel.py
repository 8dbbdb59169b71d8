"""The waveform and spectrogram under the trajectory editor's timeline: computed in a worker, cached per
utterance, aligned with the phones and the cursor at every zoom and scroll (needs a display)."""
from __future__ import annotations

import copy
import threading
import wave
from dataclasses import replace

import numpy as np
import pytest

pytestmark = pytest.mark.gui

SR = 16000


def _wav(path, seconds, loud_from):
    """Silence, then from ``loud_from`` s a harmonic sound (dark in the spectrogram)."""
    t = np.arange(int(seconds * SR)) / SR
    x = np.where(t >= loud_from, sum(np.sin(2 * np.pi * 150 * k * t) / k for k in range(1, 20)), 0.0)
    with wave.open(str(path), "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(SR)
        w.writeframes(np.rint(0.3 * x / np.abs(x).max() * 32767).astype("<i2").tobytes())
    return path


@pytest.fixture(scope="module")
def sound_manifold(app_manifold, tmp_path_factory):
    """The small talker with audio for its first two utterances (the third has none, the fourth a broken file)."""
    d = tmp_path_factory.mktemp("audio")
    c = app_manifold.corpus_
    utts = list(c.utterances)
    for k in (0, 1):
        u = utts[k]
        utts[k] = replace(u, audio=str(_wav(d / f"{u.id}.wav", u.n_frames / c.rate, 0.5 * u.n_frames / c.rate)))
    bad = d / "broken.wav"
    bad.write_bytes(b"RIFF....not a wave")
    utts[3] = replace(utts[3], audio=str(bad))
    m = copy.copy(app_manifold)
    m.corpus_ = replace(c, utterances=utts)
    return m


@pytest.fixture(scope="module")
def window(qapp, sound_manifold, main_window_factory):
    with main_window_factory(qapp, sound_manifold) as w:
        # the sound's room alone: no channel or gesture tier under it (tests/app/views/test_condition_views.py)
        w.editor.set_channels([])
        w.editor.set_gesture_track(None)
        yield w


def _load(ed, qtbot, uid):
    ed.set_source("utterance")
    ed.utt_box.setCurrentIndex(ed.utt_box.findData(uid))
    ed.load()


def _shown(ed, qtbot):
    qtbot.waitUntil(lambda: ed.sound.shown_at is not None, timeout=20000)


def test_the_sound_is_computed_off_the_gui_thread_and_drawn_under_the_phones(window, qtbot, qapp, sound_manifold):
    ed = window.editor
    ed.sound_track.clear_cache()
    u = sound_manifold.corpus_.utterances[0]
    threads = []
    import engine.phonetics.spectrogram as E

    real = E.sound_display

    def spy(*a, **k):
        threads.append(threading.current_thread())
        return real(*a, **k)

    E.sound_display = spy
    try:
        _load(ed, qtbot, u.id)
        # Load returned before the spectrogram exists: it is computed in a worker thread
        assert ed.sound.display is None and ed.sound_track.runner is not None
        assert ed.sound.isVisibleTo(ed) and "computing" in ed.sound.message
        _shown(ed, qtbot)
    finally:
        E.sound_display = real
    assert threads and threads[0] is not threading.main_thread()
    d = ed.sound.display
    assert d.duration == pytest.approx(u.n_frames / sound_manifold.corpus_.rate, abs=1e-3)
    assert d.spectrogram.max_frequency == 8000 and d.spectrogram.window_length == 0.005
    # the phones above, the sound below, in one scrolled strip as wide as the timeline
    assert ed.sound.geometry().top() == ed.timeline.geometry().bottom() + 1
    assert ed.sound.width() == ed.timeline.width()
    assert ed.scroll.height() >= ed.timeline.height() + ed.sound.height()
    # silence then sound: the spectrogram is white before the onset and dark after it
    from PySide6 import QtGui

    qtbot.waitUntil(lambda: ed.sound.width() > 200)
    img = ed.sound.grab().toImage()
    top = ed.sound.WAVE_HEIGHT + ed.sound.GAP
    rows = range(top + 5, top + ed.sound.SPEC_HEIGHT - 5, 4)

    def grey_at(t):
        x = int(ed.sound.time_x(t))
        return np.mean([QtGui.qGray(img.pixel(x, y)) for y in rows])

    dur = d.duration
    assert grey_at(0.25 * dur) > 250 and grey_at(0.75 * dur) < 200


def test_zoom_scroll_and_the_cursor_move_sound_and_phones_together(window, qtbot, qapp, sound_manifold):
    from PySide6 import QtCore

    ed = window.editor
    u = sound_manifold.corpus_.utterances[1]
    _load(ed, qtbot, u.id)
    _shown(ed, qtbot)
    rate = sound_manifold.corpus_.rate
    vp = ed.scroll.viewport()
    for zoom in (1.0, 4.0, 16.0):
        ed.set_zoom(zoom)
        bar = ed.scroll.horizontalScrollBar()
        bar.setValue(bar.maximum() // 2)
        qapp.processEvents()
        assert ed.sound.width() == ed.timeline.width()
        for t in (0.1, 0.5 * u.n_frames / rate, (u.n_frames - 1) / rate):
            xs = ed.sound.mapTo(vp, QtCore.QPoint(int(round(ed.sound.time_x(t))), 0)).x()
            xt = ed.timeline.mapTo(vp, QtCore.QPoint(int(round(ed.timeline._x(t * rate))), 0)).x()
            assert xs == xt, (zoom, t)
        for p in u.phones:  # the phone boundaries drawn through the sound are the timeline's
            assert ed.sound.time_x(p.start) == pytest.approx(ed.timeline._x(p.start * rate))
    ed.set_zoom(1.0)
    window.state.set_playback(10)
    qtbot.waitUntil(lambda: ed.sound.cursor == 10 and ed.timeline.cursor == 10, timeout=3000)


def test_each_utterance_is_computed_once_and_served_from_the_cache(window, qtbot, sound_manifold):
    ed = window.editor
    a, b = (u.id for u in sound_manifold.corpus_.utterances[:2])
    _load(ed, qtbot, a)
    _shown(ed, qtbot)
    _load(ed, qtbot, b)
    _shown(ed, qtbot)
    first = ed.sound.display
    _load(ed, qtbot, a)
    assert ed.sound.display is not None and ed.sound_track.runner is None  # at once, no worker
    _load(ed, qtbot, b)
    assert ed.sound.display is first


def test_no_audio_hides_the_sound_and_a_broken_file_says_why(window, qtbot, sound_manifold):
    ed = window.editor
    c = sound_manifold.corpus_
    _load(ed, qtbot, c.utterances[2].id)
    assert not ed.sound.isVisibleTo(ed) and ed.tracks.height() == ed.timeline.height()
    _load(ed, qtbot, c.utterances[3].id)
    qtbot.waitUntil(lambda: ed.sound_track.error is not None, timeout=20000)
    assert "broken.wav" in ed.sound.message and ed.sound.display is None
    ed.set_text("m 0.2 aa 0.3", source="phones")  # typed phones: no recording, no sound
    assert not ed.sound.isVisibleTo(ed)


def test_the_sound_box_hides_and_shows_it_and_is_kept_in_the_session(window, qtbot, sound_manifold):
    ed = window.editor
    _load(ed, qtbot, sound_manifold.corpus_.utterances[0].id)
    _shown(ed, qtbot)
    h = ed.scroll.height()
    ed.sound_box.setChecked(False)
    assert not ed.sound.isVisibleTo(ed) and ed.scroll.height() == h - ed.sound.height()
    assert ed.settings()["sound"] is False
    ed.apply_settings({**ed.settings(), "sound": True})
    assert ed.sound.isVisibleTo(ed) and ed.scroll.height() == h


def test_a_click_on_the_spectrogram_sets_the_cursor_and_a_drag_selects(window, qtbot, sound_manifold):
    from PySide6 import QtCore

    ed, s = window.editor, window.state
    u = sound_manifold.corpus_.utterances[0]
    _load(ed, qtbot, u.id)
    _shown(ed, qtbot)
    rate = sound_manifold.corpus_.rate
    y = ed.sound.WAVE_HEIGHT + ed.sound.GAP + 30                     # on the spectrogram
    at = lambda f: QtCore.QPoint(int(round(ed.sound.frame_x(f))), y)  # noqa: E731
    qtbot.mouseClick(ed.sound, QtCore.Qt.MouseButton.LeftButton, pos=at(25))
    assert abs(ed.timeline.cursor - 25) <= 1 and s.playback == ed.timeline.cursor
    assert s.frame == u.start + ed.timeline.cursor                    # and the manifold view selects its state
    qtbot.mousePress(ed.sound, QtCore.Qt.MouseButton.LeftButton, pos=at(10))
    qtbot.mouseMove(ed.sound, at(40))
    qtbot.mouseRelease(ed.sound, QtCore.Qt.MouseButton.LeftButton, pos=at(40))
    a, b = ed.timeline.time_selection
    assert abs(a - 10) <= 1 and abs(b - 40) <= 1 and ed.sound.time_selection == (a, b)
    assert rate > 0
    ed.set_time_selection(None)


def test_the_editor_keeps_no_room_for_a_sound_that_is_off_or_absent(window, qtbot, sound_manifold):
    """With the sound off (or none), the editor's dock shrinks to what it shows; the layout saved
    while a sound showed does not bring the empty room back."""
    ed = window.editor
    dock = window.docks["editor"]
    _load(ed, qtbot, sound_manifold.corpus_.utterances[0].id)
    _shown(ed, qtbot)
    qtbot.waitUntil(lambda: abs(ed.height() - ed.needed_height()) <= 4, timeout=3000)  # as tall as it needs
    tall = dock.height()
    ed.sound_box.setChecked(False)
    qtbot.waitUntil(lambda: dock.height() <= tall - ed.sound.height() + 12, timeout=3000)
    assert ed.height() - ed.needed_height() <= 4                       # no dead space under the controls
    ed.sound_box.setChecked(True)
    qtbot.waitUntil(lambda: dock.height() >= tall - 12, timeout=3000)
    _load(ed, qtbot, sound_manifold.corpus_.utterances[2].id)          # no audio: the room goes
    qtbot.waitUntil(lambda: dock.height() <= tall - ed.sound.height() + 12, timeout=3000)
    _load(ed, qtbot, sound_manifold.corpus_.utterances[0].id)
    _shown(ed, qtbot)
    window.settings.save_layout(window)                                # closed while the sound showed
    from app.main_window import MainWindow

    w2 = MainWindow(sound_manifold, source={"path": None, "preset": "small"}, settings=window.settings)
    try:
        w2.resize(window.size())
        w2.show()
        qtbot.waitUntil(lambda: w2.editor.height() > 0, timeout=3000)
        qtbot.waitUntil(lambda: w2.editor.height() - w2.editor.needed_height() <= 4, timeout=3000)  # no room
    finally:
        w2.close()


@pytest.mark.parametrize("size", [(1280, 720), (1600, 1000)])
def test_a_laptops_screen_keeps_the_3d_view_tall_and_clips_nothing(window, qtbot, qapp, sound_manifold, size,
                                                                   tab_bar_probe):
    """1280 x 720 with an utterance's sound shown (the tallest editor): the manifold view keeps half the
    window's height, the clusters table five rows, the lips a usable view; no button, box or combo is cut,
    every combo shows its whole text, the clusters' note clear of the tab bar, no empty room in the editor."""
    from PySide6 import QtWidgets

    w, ed = window, window.editor
    w.resize(*size)
    _load(ed, qtbot, sound_manifold.corpus_.utterances[0].id)
    _shown(ed, qtbot)
    w.docks["clusters"].raise_()
    for _ in range(10):
        qapp.processEvents()
    qtbot.waitUntil(lambda: abs(ed.height() - ed.needed_height()) <= 4, timeout=3000)   # no dead space
    assert w.size().toTuple() == size
    assert w.manifold_view.plotter.interactor.height() >= size[1] / 2
    table = w.clusters.table
    assert table.viewport().height() >= 5 * table.rowHeight(0)
    assert w.lip_view.plotter.interactor.height() >= 120
    def nothing_cut():
        for x in w.findChildren(QtWidgets.QAbstractButton) + w.findChildren(QtWidgets.QComboBox):
            if (x.window() is not w or not x.isVisible() or x.visibleRegion().isEmpty()
                    or x.objectName().startswith("qt_")):
                continue  # (what a dock's other tab hides; Qt's own dock title buttons place themselves)
            if not isinstance(x.parentWidget(), QtWidgets.QTabBar):
                assert x.width() >= x.minimumSizeHint().width(), (type(x).__name__,
                                                                  x.text() if hasattr(x, "text") else "")
                r = x.mapTo(w, x.rect().topLeft())
                assert 0 <= r.x() and r.x() + x.width() <= w.width() and r.y() + x.height() <= w.height(), x
            if isinstance(x, QtWidgets.QComboBox):
                assert x.fontMetrics().horizontalAdvance(x.currentText()) <= x.width() - 20, x.currentText()

    nothing_cut()
    w.docks["scree"].raise_()                                                # the other tab of the pair
    for _ in range(5):
        qapp.processEvents()
    nothing_cut()
    w.docks["clusters"].raise_()
    for _ in range(5):
        qapp.processEvents()
    note, tabs = w.clusters.note, w.findChildren(QtWidgets.QTabBar)
    box = note.geometry().translated(note.parentWidget().mapTo(w, note.parentWidget().rect().topLeft()))
    for t in tabs:
        if t.isVisible():
            corner = t.parentWidget().mapTo(w, t.parentWidget().rect().topLeft())
            assert not box.intersects(t.geometry().translated(corner))
    tab_bar_probe(w)
    # View > Small multiples: a tab beside the lips, in front, its text inside its dock (it overprinted the
    # editor's toolbar as a third dock in the column); hidden again, no tab is left naming it
    multiples = w.docks["multiples"]
    multiples.toggleViewAction().trigger()
    for _ in range(10):
        qapp.processEvents()
    assert multiples.isVisible() and w.docks["lips"] in w.tabifiedDockWidgets(multiples)
    assert multiples.geometry().intersects(w.rect())  # the tab in front
    sm = w.small_multiples
    label = sm.placeholder if sm.field is None else sm.caption
    top, box = label.mapTo(w, label.rect().topLeft()), multiples.geometry()
    assert label.isVisible() and box.contains(top) and top.y() + label.height() <= box.bottom() + 1
    assert w.manifold_view.plotter.interactor.height() >= size[1] / 2
    tab_bar_probe(w)
    multiples.toggleViewAction().trigger()
    w.docks["lips"].raise_()
    for _ in range(10):
        qapp.processEvents()
    assert multiples.isHidden()
    tab_bar_probe(w)
    w.resize(1300, 850)
