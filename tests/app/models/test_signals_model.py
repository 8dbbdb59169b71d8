"""The signals under the timeline (Qt-free): channels, the gestures of one track, and what a session keeps of them."""
from __future__ import annotations

import json

import numpy as np
import pytest

from app.models.signals import LANDMARK_WORDS, Signals, SignalsError, landmark_colour
from app.models.state import AppState
from engine.recordings.signals.gestures import LANDMARKS


@pytest.fixture(scope="module")
def found(app_manifold):
    sig = Signals(app_manifold.corpus_)
    return sig, sig.find()


def test_defaults_show_the_aperture_and_find_its_gestures(app_manifold, found):
    sig, gs = found
    assert sig.panel.channels == ("lip_aperture",) and sig.gesture_track == "lip_aperture"
    assert sig.gesture_choices() == ["lip_aperture", "lip_protrusion"]
    assert gs.track == "lip_aperture" and len(gs) > 10 and gs.times.shape == (len(gs), len(LANDMARKS))
    ok = np.all(np.isfinite(gs.times), axis=1)
    assert ok.any() and np.all(np.diff(gs.times[ok], axis=1) >= 0)  # GONS <= PVEL <= ... <= GOFFS


def test_an_edited_landmark_survives_a_session_and_reads_its_speed_again(app_manifold, found):
    sig, gs = found
    sig.use(gs)
    assert not sig.edited and sig.settings()["gestures"] is None  # nothing edited: nothing kept but the choices
    g = int(np.flatnonzero(np.all(np.isfinite(gs.times), axis=1))[0])
    lo, hi = sig.editor.bounds(g, "MAXC")
    t = sig.editor.move(g, "MAXC", 0.5 * (lo + hi) + 0.25 * (hi - lo))
    assert sig.edited
    d = json.loads(json.dumps(sig.settings()))  # what a session file holds
    assert d["channels"] == ["lip_aperture"] and d["gesture_track"] == "lip_aperture"
    back = Signals.from_settings(app_manifold.corpus_, d)
    back.use(back.find())
    back.restore(d)
    assert back.edited
    np.testing.assert_allclose(back.gestures.times, sig.gestures.times, atol=1e-6, equal_nan=True)
    assert back.gestures.times[g, LANDMARKS.index("MAXC")] == pytest.approx(t, abs=1e-6)
    # the times are kept to 1 us, so the value at MAXC is read again at a time 1 us off at most
    np.testing.assert_allclose(back.gestures.maxc_value, sig.gestures.maxc_value, atol=1e-4, equal_nan=True)
    sig.editor.undo()
    assert sig.gestures.times[g, LANDMARKS.index("MAXC")] == gs.times[g, LANDMARKS.index("MAXC")]


def test_settings_that_do_not_fit_the_corpus_are_refused_by_name(app_manifold, found):
    c = app_manifold.corpus_
    with pytest.raises(SignalsError, match="gesture track 'speed_tongue'.*gives gestures of lip_aperture"):
        Signals(c, gesture_track="speed_tongue")
    with pytest.raises(SignalsError, match="gesture threshold 1.5: a share of the peak speed"):
        Signals(c, threshold=1.5)
    sig, gs = found
    d = sig.settings() | {"gestures": {"lowpass_hz": 15.0, "utterance": ["nope"], "times": [[0.1] * 7]}}
    with pytest.raises(SignalsError, match="name utterance\\(s\\) nope this corpus lacks"):
        sig.gestures_from_settings(d)
    # a channel the corpus lacks is left out, not fatal
    assert Signals.from_settings(c, {"channels": ["lip_aperture", "rms_UL"]}).panel.channels == ("lip_aperture",)


def test_every_landmark_has_its_own_palette_colour(app_manifold):
    pal = AppState(app_manifold).palette
    cols = {tuple(np.round(landmark_colour(pal, k), 4)) for k in LANDMARK_WORDS}
    assert len(cols) == len(LANDMARKS)


def test_a_corpus_too_slow_for_the_default_cut_off_shows_raw_positions(app_manifold):
    from dataclasses import replace

    from app.models.signals import default_lowpass

    assert default_lowpass(60.0) == 15.0 and default_lowpass(250.0) == 15.0
    assert default_lowpass(30.0) is None  # 15 Hz is the Nyquist frequency of a 30 Hz video
    video_rate = replace(app_manifold.corpus_, rate=30.0)
    sig = Signals(video_rate)
    assert sig.panel.lowpass_hz is None and sig.panel.channels == ("lip_aperture",)
    back = Signals.from_settings(video_rate, {"channels": ["lip_aperture"]})
    assert back.panel.lowpass_hz is None
    with pytest.raises(SignalsError, match="low-pass cut-off 20 Hz: must be above 0 and below the Nyquist"):
        Signals.from_settings(video_rate, {"lowpass_hz": 20.0})
