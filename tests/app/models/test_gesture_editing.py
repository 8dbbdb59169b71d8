"""Adjusting gestural landmarks in a Qt-free model: moves clamped to the landmark order, values re-measured,
clearing and removing, undo and redo, picking and what the tier and the manifold marks draw."""
from __future__ import annotations

import numpy as np
import pytest

from app.models.gesture_editing import GestureEditor
from engine.recordings.corpus import Corpus, Utterance
from engine.recordings.signals.gestures import find_gestures


def _corpus():
    """Two utterances of a lip pair closing and opening three times (minima at 0.2, 0.6 and 1.0 s), 250 Hz."""
    rate, n = 250.0, 300
    t = np.arange(n) / rate
    gap = 8 + 6 * np.cos(2 * np.pi * 2.5 * t)
    F = np.zeros((n, 6), np.float32)
    F[:, 2] = gap / 2
    F[:, 5] = -gap / 2
    F = np.vstack([F, F])
    return Corpus(frames=F, rate=rate, utterances=[Utterance("a", 0, n), Utterance("b", n, 2 * n)],
                  point_names=["UL", "LL"], point_roles=["upper_lip", "lower_lip"])


@pytest.fixture
def editor():
    c = _corpus()
    return GestureEditor(c, find_gestures(c, "lip_aperture"))


def test_moves_are_clamped_to_the_landmark_order_and_values_follow(editor):
    gs = editor.gestures
    assert len(gs) == 6 and np.allclose(gs.times[:3, 3], [0.2, 0.6, 1.0], atol=2e-3)
    events = []
    editor.changed.connect(lambda kind, g: events.append((kind, g)))
    lo, hi = editor.bounds(0, "PVEL")
    assert lo == pytest.approx(gs.times[0, 0]) and hi == pytest.approx(gs.times[0, 2])
    got = editor.move(0, "PVEL", 0.0)  # before the onset: stops at it
    assert got == pytest.approx(gs.times[0, 0])
    assert editor.gestures.peak_velocity[0, 0] == pytest.approx(0.2 * gs.peak_velocity[0, 0], rel=0.05)
    editor.move(0, "MAXC", 0.21)
    assert editor.gestures.maxc_value[0] > gs.maxc_value[0]  # off the minimum: a wider aperture
    assert events == [("move", 0), ("move", 0)]
    assert editor.gestures.times[1].tolist() == gs.times[1].tolist()  # other gestures untouched


def test_undo_redo_clear_and_remove(editor):
    gs0 = editor.gestures
    editor.move(1, "GONS", gs0.times[1, 0] + 0.01)
    editor.clear(1, "GOFFS")
    assert np.isnan(editor.gestures.times[1, 6])
    editor.remove(0)
    assert len(editor.gestures) == 5
    assert editor.undo() and len(editor.gestures) == 6
    assert editor.undo() and np.isfinite(editor.gestures.times[1, 6])
    assert editor.undo() and editor.gestures is gs0 and not editor.can_undo and not editor.undo()
    assert editor.redo() and editor.gestures.times[1, 0] == pytest.approx(gs0.times[1, 0] + 0.01)
    editor.move(2, "NONS", gs0.times[2, 2] - 0.005)  # a new edit drops what could be redone
    assert not editor.can_redo


def test_points_picking_and_frames(editor):
    gs = editor.gestures
    pts = editor.points("b")
    assert sorted({p[2] for p in pts}) == [3, 4, 5] and len(pts) == int(np.isfinite(gs.times[3:]).sum())
    assert pts == sorted(pts, key=lambda p: (p[0], p[3]))
    g, j = editor.nearest("b", gs.times[4, 3] + 0.004)
    assert (g, j) == (4, 3)
    assert editor.nearest("b", gs.times[4, 3] + 0.004, landmarks=["GONS"]) is None
    assert editor.nearest("a", 5.0) is None
    f = editor.frames("b")
    assert f.shape == (3, 7) and (f[f >= 0] >= 300).all()
    with pytest.raises(ValueError, match="expected one of GONS"):
        editor.move(0, "PEAK", 0.1)
