"""Sparse lip markers as a closed contour tube: ordering, the mirrored corner, interpolation, mesh export."""
import numpy as np
import pytest

from engine.corpus import Corpus, Utterance
from engine.lipcontour import LipContour, mesh_geometry

# UL, LL, left corner, jaw (x anterior, y lateral, z vertical)
P = np.array([[10.0, 0.0, 6.0], [8.0, 0.0, -8.0], [-2.0, 25.0, -1.0], [-5.0, 0.0, -30.0]])
ROLES = ["upper_lip", "lower_lip", "left_corner", "jaw"]


def test_contour_passes_through_the_lip_points_and_mirrors_the_missing_corner():
    lc = LipContour(n_samples=64).fit(P, ROLES)
    assert lc.mirror_of_ == 2 and lc.lateral_ == 1 and 3 not in lc.lip_points_ and len(lc.lip_points_) == 4
    C = lc.contour(P)
    for p in P[:3]:  # the spline interpolates its knots (each is a sample: chord-length spacing)
        assert np.linalg.norm(C - p, axis=1).min() < 0.02 * np.ptp(P[:3], axis=0).max() + 1.0
    # the estimated right corner: the left one mirrored across y (the lateral axis) about the lip line
    far = C[np.argmin(C[:, 1])]
    np.testing.assert_allclose(far[1], -25.0, atol=1.5)
    # tube: every vertex at the radius from its contour sample
    V = lc.transform(P)
    assert V.shape == (64 * 8, 3) and lc.faces_.shape == (64 * 8 * 2, 3) and lc.faces_.max() == len(V) - 1
    d = np.linalg.norm(V.reshape(64, 8, 3) - C[:, None], axis=2)
    np.testing.assert_allclose(d, lc.radius_, rtol=1e-4)
    # frames animate with the same topology
    frames = np.stack([P, P + [0, 0, 1.0]])
    np.testing.assert_allclose(lc.transform(frames)[1] - lc.transform(frames)[0], [[0, 0, 1.0]] * len(V), atol=1e-4)


def test_contour_needs_lip_points():
    with pytest.raises(ValueError, match=r"2 lip points.*needs 4 to 20"):
        LipContour().fit(P[:2], ROLES[:2])
    many = np.random.default_rng(0).normal(size=(25, 3))
    with pytest.raises(ValueError, match=r"25 lip points"):
        LipContour().fit(many)
    ring = np.c_[np.cos(np.linspace(0, 6, 12)), np.sin(np.linspace(0, 6, 12)), np.zeros(12)] * 20
    shuffled = ring[np.random.default_rng(1).permutation(12)]
    lc = LipContour().fit(shuffled)  # no roles: every point, ordered by angle around the mouth
    C = lc.contour(shuffled)
    assert np.allclose(np.linalg.norm(C[:, :2], axis=1), 20, atol=1.5)


def test_mesh_geometry_for_sparse_markers_and_meshes():
    F = np.stack([P.ravel(), (P + [0, 0, 0.5]).ravel()] * 3).astype(np.float32)
    c = Corpus(frames=F, rate=60, utterances=[Utterance("u", 0, 6)], point_names=["UL", "LL", "ML", "JAW"],
               point_roles=ROLES)
    pts, faces, note = mesh_geometry(F, c)
    assert pts.shape == (6, 48 * 8, 3) and faces.shape == (48 * 8 * 2, 3)
    assert note.startswith("lip contour tube through") and "mirrored corner" in note
    bare = Corpus(frames=F, rate=60, utterances=[Utterance("u", 0, 6)])
    assert mesh_geometry(F, bare)[1] is None
