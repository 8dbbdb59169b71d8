"""Sparse lip markers as a closed contour tube: ordering, the mirrored corner, interpolation, mesh export."""
import numpy as np
import pytest

from engine.recordings.corpus import Corpus, Utterance
from engine.recordings.lipcontour import LipContour, mesh_geometry

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


@pytest.mark.parametrize("fmt,binary", [("obj", False), ("ply", False), ("ply", True)])
def test_mesh_export_labels_the_sensors_at_their_positions(tmp_path, fmt, binary):
    from engine.io import read_mesh, read_vertex_labels, write_mesh_sequence

    F = np.stack([P.ravel(), (P + [0, 0, 0.5]).ravel(), (P * 1.1).ravel()]).astype(np.float32)
    c = Corpus(frames=F, rate=60, utterances=[Utterance("u", 0, 3)], point_names=["UL", "LL", "left corner", "JAW"],
               point_roles=ROLES)
    pts, faces, note, labels = mesh_geometry(F, c, sensors=True)
    n_tube = 48 * 8
    assert pts.shape == (3, n_tube + 3, 3) and faces.max() < n_tube  # the sensor vertices are not in the tube
    # one vertex per lip sensor after the tube, in contour order; the jaw is not on the contour
    assert sorted(n for n, _ in labels) == ["LL", "UL", "left corner"]
    assert [v for _, v in labels] == [n_tube, n_tube + 1, n_tube + 2]
    assert "3 labelled sensors" in note
    files = write_mesh_sequence(tmp_path, pts, faces=faces, format=fmt, binary=binary, labels=labels)
    idx = {"UL": 0, "LL": 1, "left corner": 2}
    for k, f in enumerate(files):
        V, Fc = read_mesh(f)
        np.testing.assert_array_equal(Fc, faces)
        got = read_vertex_labels(f)
        assert got == labels
        for name, v in got:  # each labelled vertex is its sensor's position in that frame
            np.testing.assert_allclose(V[v], F[k].reshape(-1, 3)[idx[name]], rtol=1e-6, atol=1e-5)
    text = files[0].read_text(errors="replace") if not binary else files[0].read_bytes()[:2000].decode("latin-1")
    if fmt == "obj":
        assert "# sensor left corner vertex" in text and "g left_corner\np " in text and "g mesh\nf " in text
    else:
        assert "comment sensor UL vertex" in text
    # bare named points: every point is its own sensor
    bare = Corpus(frames=F, rate=60, utterances=[Utterance("u", 0, 3)], point_names=["a", "b", "c", "d"])
    assert mesh_geometry(F, bare, sensors=True)[3] == [("a", 0), ("b", 1), ("c", 2), ("d", 3)]


def test_vertex_labels_are_validated(tmp_path):
    from engine.io import write_obj

    with pytest.raises(ValueError, match=r"vertex label 0 \('UL'\): vertex 4 is outside 0..3"):
        write_obj(tmp_path / "a.obj", P, labels=[("UL", 4)])
    with pytest.raises(ValueError, match="one line"):
        write_obj(tmp_path / "a.obj", P, labels=[("U\nL", 0)])
    assert not (tmp_path / "a.obj").exists()
