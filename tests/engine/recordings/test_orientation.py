"""The talker's anatomical frame from the point roles, whatever the recording system's axes: every permutation and
flip of an articulograph corpus's x, y, z gives the same front view (upper lip above lower lip, the talker's left
corner on the viewer's right, the lips towards the viewer)."""
import itertools
from dataclasses import replace

import numpy as np
import pytest

from engine.io.readers.matrix import corpus_from_matrix
from engine.recordings.layouts import BUILTIN
from engine.recordings.orientation import AxesError, anatomical_frame, parse_axes
from engine.talker.multispeaker import generate_recordings

#: the generator's axes: x anterior, y the talker's left, z up -> view rows (left, up, forward) in its coordinates
CANONICAL = np.array([[0.0, 1.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]])
SIGNED_PERMUTATIONS = [np.diag(s) @ np.eye(3)[list(p)] for p in itertools.permutations(range(3))
                       for s in itertools.product((1.0, -1.0), repeat=3)]


@pytest.fixture(scope="module")
def recording():
    r = generate_recordings(n_speakers=1, n_utterances=1, duration_s=(1.0, 1.0), seed=7)[0]
    return corpus_from_matrix("ABCFIA01.mat", r.matrix, BUILTIN["ema7x6"], rate=r.rate, points="all")


def _axes(corpus, A, keep=None):
    """The corpus in another recording system: data' = A @ data per point; ``keep`` selects points."""
    P = corpus.frames.reshape(corpus.n_frames, -1, 3) @ A.T
    names, roles = list(corpus.point_names), list(corpus.point_roles)
    if keep is not None:
        idx = [names.index(n) for n in keep]
        P, names, roles = P[:, idx], [names[i] for i in idx], [roles[i] for i in idx]
    return replace(corpus, frames=P.reshape(corpus.n_frames, -1).astype(np.float32), point_names=names,
                   point_roles=roles)


def _view_of(corpus, frame, name):
    P = frame.view(corpus.frames.reshape(corpus.n_frames, -1, 3).mean(axis=0))
    return P[corpus.point_names.index(name)]


@pytest.mark.parametrize("k", range(len(SIGNED_PERMUTATIONS)))
def test_every_axis_order_and_flip_gives_the_front_view(recording, k):
    A = SIGNED_PERMUTATIONS[k]
    c = _axes(recording, A, keep=["UL", "LL", "LC", "RC"])  # the four lip sensors import keeps
    f = anatomical_frame(c)
    assert f.source == "roles"
    np.testing.assert_allclose(f.matrix @ A, CANONICAL, atol=1e-9)  # snapped to the data's own axes
    assert f.mirrored == (np.linalg.det(A) < 0)
    ul, ll, lc, rc = (_view_of(c, f, n) for n in ("UL", "LL", "LC", "RC"))
    assert ul[1] > ll[1] + 5  # upper lip above the lower lip (mm)
    assert lc[0] > rc[0] + 30  # the talker's left corner on the viewer's right
    assert min(ul[2], ll[2]) > max(lc[2], rc[2])  # the lips nearer the viewer than the corners


@pytest.mark.parametrize("k", [0, 5, 13, 22, 31, 47])
def test_one_corner_and_the_tongue_give_the_frame(recording, k):
    A = SIGNED_PERMUTATIONS[k]
    c = _axes(recording, A, keep=["UL", "LL", "LC", "TT", "TB"])  # one corner: left and right from it alone
    f = anatomical_frame(c)
    np.testing.assert_allclose(f.matrix @ A, CANONICAL, atol=1e-9)
    c = _axes(recording, A, keep=["UL", "LL", "TT", "TB", "TD"])  # no corner: forward from the tongue
    f = anatomical_frame(c)
    np.testing.assert_allclose(f.matrix[1:] @ A, CANONICAL[1:], atol=1e-9)  # up and forward; left follows


@pytest.mark.parametrize("swap, fx, fy", list(itertools.product((False, True), (1.0, -1.0), (1.0, -1.0))))
def test_a_mid_sagittal_2d_corpus_gets_a_profile(recording, swap, fx, fy):
    """2-D (x anterior, z up of the generator; every order and flip): x forward, y up in the view."""
    P = recording.frames.reshape(recording.n_frames, -1, 3)[:, :, [0, 2]]
    B = np.diag([fx, fy]) @ (np.eye(2)[[1, 0]] if swap else np.eye(2))
    keep = [recording.point_names.index(n) for n in ("UL", "LL", "TT", "TB")]
    c = replace(recording, frames=(P[:, keep] @ B.T).reshape(recording.n_frames, -1).astype(np.float32), dims=2,
                point_names=["UL", "LL", "TT", "TB"], point_roles=["upper_lip", "lower_lip", "tongue", "tongue"])
    f = anatomical_frame(c)
    np.testing.assert_allclose(f.matrix @ B, np.eye(2), atol=1e-9)


def test_an_oblique_recording_is_turned_not_snapped(recording):
    t = np.radians(40)
    R = np.array([[np.cos(t), -np.sin(t), 0], [np.sin(t), np.cos(t), 0], [0, 0, 1]])  # head turned 40 degrees
    c = _axes(recording, R, keep=["UL", "LL", "LC", "RC"])
    f = anatomical_frame(c)
    assert "snapped" not in f.note and "deg off" in f.describe()
    lc, rc = _view_of(c, f, "LC"), _view_of(c, f, "RC")
    assert abs(lc[2] - rc[2]) < 1.0 and lc[0] > rc[0]  # the corners level in depth: a true front view


def test_axes_given_on_import_win_and_are_checked(recording):
    A = SIGNED_PERMUTATIONS[9]
    c = replace(_axes(recording, A, keep=["UL", "LL", "LC", "RC"]), point_roles=None)
    f = anatomical_frame(c)
    assert f.source == "none" and "--axes" in f.note
    spec = ",".join(f"{'xyz'[j]}={w}" for j, w in enumerate(_words(A)))
    g = anatomical_frame(replace(c, axes=parse_axes(spec, 3).spec()))
    assert g.source == "axes"
    np.testing.assert_allclose(g.matrix @ A, CANONICAL)
    assert parse_axes("x=anterior, y=left, z=superior", 3).spec() == "x=forward,y=left,z=up"
    for bad, msg in (("x=forward,y=left", "each of the 3 axes"), ("x=forward,y=forward,z=up", "cover left, up"),
                     ("x=ahead,y=left,z=up", "direction 'ahead'"), ("w=up,y=left,z=forward", "axis 'w'"),
                     ("x=forward,x=left,z=up", "given twice")):
        with pytest.raises(AxesError, match=msg):
            parse_axes(bad, 3)


def _words(A):
    """Direction words of the data axes of ``A @ generator``: data axis j is A[j] of (forward, left, up)."""
    names = (("forward", "back"), ("left", "right"), ("up", "down"))
    out = []
    for row in A:
        i = int(np.argmax(np.abs(row)))
        out.append(names[i][0] if row[i] > 0 else names[i][1])
    return out


def test_no_roles_or_no_lips_keep_the_data_axes(recording):
    c = replace(recording, point_roles=[""] * recording.n_points)
    f = anatomical_frame(c)
    assert f.source == "none" and np.array_equal(f.matrix, np.eye(3)) and "upper_lip and lower_lip" in f.note
