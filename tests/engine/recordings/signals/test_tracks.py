"""Derived tracks: zero-phase low-pass per utterance, tangential velocity, protrusion along the talker's forward
axis, positions along the talker's axes, rms as a track -- checked against values computed by hand."""
from __future__ import annotations

import numpy as np
import pytest

from engine.recordings.corpus import Corpus, Utterance
from engine.recordings.signals.filters import check_cutoff, lowpass, velocity
from engine.recordings.signals.tracks import TrackError, available_tracks, column_name, derived_track

RATE = 250.0


def test_lowpass_is_zero_phase_and_keeps_utterances_apart():
    t = np.arange(500) / RATE
    slow = np.sin(2 * np.pi * 3 * t)
    fast = 0.5 * np.sin(2 * np.pi * 60 * t)
    y = lowpass(slow + fast, [[0, 500]], RATE, cutoff_hz=15)
    inner = slice(50, 450)
    np.testing.assert_allclose(y[inner], slow[inner], atol=0.01)  # 3 Hz passed without a shift, 60 Hz removed
    step = np.r_[np.zeros(100), np.full(100, 10.0)]
    z = lowpass(step, [[0, 100], [100, 200]], RATE, cutoff_hz=15)
    np.testing.assert_allclose(z[:100], 0, atol=1e-9)  # nothing leaks across the utterance boundary
    np.testing.assert_allclose(z[100:], 10, atol=1e-9)
    with pytest.raises(ValueError, match=r"below the Nyquist frequency 30 Hz of 60 Hz frames"):
        check_cutoff(30, 60)


def test_velocity_is_per_second_within_utterances():
    x = np.r_[np.arange(10) * 2.0, 100 + np.arange(5) * -1.0]
    v = velocity(x, [[0, 10], [10, 15]], 50.0)
    np.testing.assert_allclose(v[:10], 100.0)
    np.testing.assert_allclose(v[10:], -50.0)


def _rotated_corpus(theta_deg=30.0, reference=True):
    """Lips protruding 2 mm forward and back at 2 Hz, closing/opening at 4 Hz, in a frame where forward is rotated
    ``theta_deg`` about the vertical from the data's x axis (a lab whose x axis is not the talker's)."""
    n = 500
    t = np.arange(n) / RATE
    prot = 2.0 * np.sin(2 * np.pi * 2 * t)
    gap = 6 + 4 * np.sin(2 * np.pi * 4 * t)
    a = np.deg2rad(theta_deg)
    fwd, left, up = np.array([np.cos(a), np.sin(a), 0]), np.array([-np.sin(a), np.cos(a), 0]), np.array([0, 0, 1.0])
    base = np.array([10.0, 20.0, 30.0])
    P = {"UL": base + 10 * fwd + np.outer(gap / 2, up) + np.outer(prot, fwd),
         "LL": base + 10 * fwd - np.outer(gap / 2, up) + np.outer(prot, fwd),
         "LC": base + 5 * fwd + 25 * left + np.zeros((n, 1)), "RC": base + 5 * fwd - 25 * left + np.zeros((n, 1))}
    roles = ["upper_lip", "lower_lip", "left_corner", "right_corner"]
    if reference:
        P["NOSE"] = base + 20 * fwd + 40 * up + np.zeros((n, 1))
        roles.append("reference")
    F = np.concatenate([np.broadcast_to(v, (n, 3)) for v in P.values()], axis=1).astype(np.float32)
    c = Corpus(frames=F, rate=RATE, utterances=[Utterance("u", 0, n)], point_names=list(P), point_roles=roles,
               axes="")
    return c, prot, gap, t


def test_protrusion_is_along_the_talkers_forward_axis_against_reference_or_mean():
    c, prot, gap, t = _rotated_corpus(30.0)
    tr = derived_track(c, "lip_protrusion", lowpass_hz=None)
    np.testing.assert_allclose(tr.values, prot - 10.0, atol=1e-3)  # lips 10 mm behind the nose sensor
    assert "reference points" in tr.description and tr.unit == "mm"
    mean = derived_track(c, "lip_protrusion", lowpass_hz=None, against="mean")
    np.testing.assert_allclose(mean.values, prot - prot.mean(), atol=1e-3)
    no_ref, *_ = _rotated_corpus(30.0, reference=False)
    np.testing.assert_allclose(derived_track(no_ref, "lip_protrusion", lowpass_hz=None).values, prot - prot.mean(),
                               atol=1e-3)
    with pytest.raises(TrackError, match="no reference points"):
        derived_track(no_ref, "lip_protrusion", against="reference")


def test_speed_is_the_length_of_the_velocity_and_axes_are_the_talkers():
    c, prot, gap, t = _rotated_corpus(30.0)
    # UL moves forward by prot and up by gap/2: speed = sqrt(prot'^2 + (gap'/2)^2)
    dprot = 2.0 * 2 * np.pi * 2 * np.cos(2 * np.pi * 2 * t)
    dgap = 4 * 2 * np.pi * 4 * np.cos(2 * np.pi * 4 * t)
    want = np.hypot(dprot, dgap / 2)
    got = derived_track(c, "speed_UL", lowpass_hz=None)
    np.testing.assert_allclose(got.values[1:-1], want[1:-1], rtol=2e-3, atol=0.05)
    assert got.unit == "mm/s"
    filt = derived_track(c, "speed_UL", lowpass_hz=15.0)  # below the cut-off: the same inside the utterance
    np.testing.assert_allclose(filt.values[30:-30], want[30:-30], rtol=0.02, atol=0.3)
    up = derived_track(c, "UL_up", lowpass_hz=None)
    np.testing.assert_allclose(up.values, gap / 2 - (gap / 2).mean(), atol=1e-3)
    fwd = derived_track(c, "LL_forward", lowpass_hz=None)
    np.testing.assert_allclose(fwd.values, prot - prot.mean(), atol=1e-3)


def test_the_list_of_tracks_and_their_column_names():
    c, *_ = _rotated_corpus()
    names = available_tracks(c)
    assert names[:2] == ["lip_aperture", "lip_protrusion"] and "speed_NOSE" in names and "RC_left" in names
    assert column_name("speed_UL") == "speed_ul" and column_name("UL_up") == "ul_up"
    with pytest.raises(TrackError, match="no point 'TT'"):
        derived_track(c, "speed_TT")
    with pytest.raises(TrackError, match="no track 'jaw_angle'"):
        derived_track(c, "jaw_angle")


def test_rms_is_a_track_when_the_file_had_it(tmp_path):
    from engine.io import read_corpus
    from engine.talker.lab_files import SOCKETS, lab_sweeps, layout_text, write_pos

    s = lab_sweeps(speakers=(("XYZ", "F"),), emotions=("NE",), texts=1, duration_s=(0.6, 0.6))[0]
    (tmp_path / "l.layout").write_text(layout_text())
    c = read_corpus(write_pos(tmp_path / "XYZFNE01.pos", s), layout=str(tmp_path / "l.layout"))
    assert "rms_UL" in available_tracks(c)
    np.testing.assert_allclose(derived_track(c, "rms_UL").values, s.rms[:, SOCKETS.index("UL")], rtol=1e-6)
