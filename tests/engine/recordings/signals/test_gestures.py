"""Gestural landmarks (findgest / anagest / ag501::FindLandmarks) against values computed by hand on signals with
known landmarks, on the Haskins samples' bilabials, and as synthesis targets and labels."""
from __future__ import annotations

import numpy as np
import pytest

from engine.recordings.signals.gestures import (
    LANDMARKS,
    find_gestures,
    gesture_key_frames,
    gestures_of_signal,
    landmark_order_ok,
    remeasure,
    target_of,
    with_gesture_labels,
)

RATE = 250.0
Q = np.arcsin(np.sqrt(0.2)) / np.pi  # where sin^2 reaches 20 % of its peak, as a share of the pulse


def closing_opening(t, x0=12.0, a=0.4, d1=0.2, b=0.7, d2=0.25, peak1=60.0, peak2=48.0):
    """A track falling from x0 with speed peak1*sin^2 over [a, a+d1], held, rising with peak2*sin^2 over [b, b+d2]:
    its landmarks are known in closed form (see ``expected``)."""
    x = np.full_like(t, x0)
    m = (t >= a) & (t < a + d1)
    u = t[m] - a
    x[m] = x0 - peak1 * (u / 2 - d1 / (4 * np.pi) * np.sin(2 * np.pi * u / d1))
    low = x0 - peak1 * d1 / 2
    x[(t >= a + d1) & (t < b)] = low
    m = (t >= b) & (t < b + d2)
    u = t[m] - b
    x[m] = low + peak2 * (u / 2 - d2 / (4 * np.pi) * np.sin(2 * np.pi * u / d2))
    x[t >= b + d2] = low + peak2 * d2 / 2
    return x


def expected(a=0.4, d1=0.2, b=0.7, d2=0.25, theta_q=Q):
    return np.array([a + d1 * theta_q, a + d1 / 2, a + d1 * (1 - theta_q), (a + d1 + b) / 2,
                     b + d2 * theta_q, b + d2 / 2, b + d2 * (1 - theta_q)])


def test_landmarks_of_a_constriction_match_the_hand_computed_values():
    t = np.arange(int(1.2 * RATE)) / RATE
    gs = gestures_of_signal(closing_opening(t), [[0, t.size]], RATE, target="min")
    assert len(gs) == 1
    np.testing.assert_allclose(gs.times[0], expected(), atol=0.5e-3)  # within half a millisecond at 250 Hz
    np.testing.assert_allclose(gs.peak_velocity[0], [60.0, 48.0], rtol=2e-3)
    assert gs.maxc_value[0] == pytest.approx(12 - 60 * 0.2 / 2)


def test_a_movement_to_a_maximum_and_another_threshold():
    t = np.arange(int(1.2 * RATE)) / RATE
    x = -closing_opening(t)  # protrusion-like: out to a peak and back
    gs = gestures_of_signal(x, [[0, t.size]], RATE, target="max", threshold=0.1)
    q10 = np.arcsin(np.sqrt(0.1)) / np.pi
    np.testing.assert_allclose(gs.times[0], expected(theta_q=q10), atol=0.5e-3)
    assert gs.maxc_value[0] == pytest.approx(-(12 - 6))


def test_gestures_per_utterance_and_one_cut_by_the_start_misses_its_onset():
    t = np.arange(int(1.2 * RATE)) / RATE
    x1 = closing_opening(t)
    x2 = closing_opening(t, a=-0.05, d1=0.2, b=0.4)  # already closing when the recording starts
    gs = gestures_of_signal(np.r_[x1, x2], [[0, t.size], [t.size, 2 * t.size]], RATE)
    assert gs.utterance.tolist() == [0, 1]
    second = gs.times[1]
    assert np.isnan(second[0])  # the movement began before the utterance: no gesture onset
    np.testing.assert_allclose(second[4:], expected(a=-0.05, b=0.4)[4:], atol=0.5e-3)
    assert landmark_order_ok(gs.times).all()


def test_low_passing_moves_the_landmarks_by_little(tmp_path):
    from engine.recordings.signals.filters import lowpass

    t = np.arange(int(1.2 * RATE)) / RATE
    rng = np.random.default_rng(0)
    x = closing_opening(t) + 0.02 * rng.normal(size=t.size)  # sensor noise
    filt = gestures_of_signal(lowpass(x, [[0, t.size]], RATE, cutoff_hz=15), [[0, t.size]], RATE)
    assert len(filt) == 1
    err = np.abs(filt.times[0] - expected())
    assert err[[0, 1, 2, 4, 5, 6]].max() < 0.006
    assert 0.6 - 0.005 <= filt.times[0, 3] <= 0.7 + 0.005  # on a flat target noise decides where in it the minimum is


def test_remeasure_reads_peak_speeds_at_moved_landmarks():
    t = np.arange(int(1.2 * RATE)) / RATE
    x = closing_opening(t)
    gs = gestures_of_signal(x, [[0, t.size]], RATE)
    times = gs.times.copy()
    times[0, 1] = 0.4 + 0.2 * 0.25  # a quarter into the pulse: speed 60 * sin^2(pi/4) = 30
    moved = remeasure(gs.with_times(times), x, [[0, t.size]])
    assert moved.peak_velocity[0, 0] == pytest.approx(30.0, rel=5e-3)
    assert moved.peak_velocity[0, 1] == pytest.approx(gs.peak_velocity[0, 1], rel=1e-3)


def test_target_kinds():
    assert target_of("lip_aperture") == "min" and target_of("lip_protrusion") == "max"
    assert target_of("UL_up", "max") == "max"
    with pytest.raises(ValueError, match="say whether its gestures move to a minimum or a maximum"):
        target_of("UL_up")


@pytest.fixture(scope="module")
def haskins(shared_data):
    from engine.io import read_corpus

    return read_corpus(sorted((shared_data / "haskins-ieee").glob("*.mat")))


def test_on_the_haskins_samples_bilabial_closures_are_found_at_their_phones(haskins):
    gs = find_gestures(haskins, "lip_aperture")
    assert len(gs) >= 8 and landmark_order_ok(gs.times).all()
    hits, total, chance = 0, 0, []
    rng = np.random.default_rng(0)
    for k, u in enumerate(haskins.utterances):
        maxc = gs.times[gs.utterance == k, 3]
        dur = u.n_frames / haskins.rate
        for p in u.phones:
            if p.label.rstrip("012") in ("P", "B", "M"):
                total += 1
                hits += bool(np.any((maxc >= p.start - 0.03) & (maxc <= p.end + 0.03)))
                # the baseline: as many times drawn at random in the utterance
                r = rng.uniform(0, dur, size=(200, maxc.size))
                chance.append(np.mean(np.any((r >= p.start - 0.03) & (r <= p.end + 0.03), axis=1)))
    assert total >= 4
    assert hits / total >= 0.75 and hits / total > np.mean(chance) + 0.3, (hits, total, np.mean(chance))


def test_on_the_haskins_samples_the_onsets_are_at_a_fifth_of_the_peak_speed(haskins):
    from engine.recordings.signals.filters import velocity
    from engine.recordings.signals.tracks import derived_track

    gs = find_gestures(haskins, "lip_aperture")
    x = derived_track(haskins, "lip_aperture").values
    v = velocity(x, haskins.bounds, haskins.rate)
    b = haskins.bounds
    for g in range(len(gs)):
        a = b[gs.utterance[g], 0]
        f = gs.times[g] * haskins.rate
        if np.isfinite(f[0]):
            at = np.interp(f[0], np.arange(b[gs.utterance[g], 1] - a), -v[a:b[gs.utterance[g], 1]])
            assert at == pytest.approx(0.2 * gs.peak_velocity[g, 0], rel=0.05, abs=0.5)


def test_landmarks_as_key_frames_and_as_labels(haskins):
    gs = find_gestures(haskins, "lip_aperture")
    u = haskins.utterances[0]
    kf = gesture_key_frames(gs, u.id, haskins.bounds, landmarks=("GONS", "MAXC"))
    assert kf.size and np.all(np.diff(kf) > 0) and kf.max() < u.n_frames
    lab = with_gesture_labels(haskins, gs, landmarks=("MAXC",))
    mids, labels, utt, *_ = lab.phone_table()
    assert set(labels.tolist()) == {"MAXC"} and len(labels) == len(gs)
    assert "gestural landmarks (MAXC) of lip_aperture" in lab.history[-1]
    full = with_gesture_labels(haskins, gs)
    assert set(full.phone_table()[1].tolist()) <= set(LANDMARKS)
