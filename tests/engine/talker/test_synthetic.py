"""The synthetic talker, its lip surface and the corpus cache."""
from __future__ import annotations

import numpy as np
import pytest

from engine.phonetics.phones import PAPER_COUNTS, PAUSE, PHONES
from engine.progress import Cancelled
from engine.recordings.corpus import Corpus
from engine.talker.lipmodel import CONTROL_NAMES, SIGNED_CONTROLS, Anatomy, LipModel, vermilion_weight
from engine.talker.synthetic import PHONE_GESTURES, SyntheticTalker, gesture_phases, load_synthetic


@pytest.fixture
def tmp_cache(tmp_path, monkeypatch):
    d = tmp_path / "cache"
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(d))
    return d


@pytest.fixture(scope="module")
def small():
    """The small preset, generated here (not from any cache)."""
    return SyntheticTalker(preset="small").generate()


def _controls(**kw):
    c = np.zeros((1, len(CONTROL_NAMES)))
    for k, v in kw.items():
        c[0, CONTROL_NAMES.index(k)] = v
    return c


# ----------------------------------------------------------------- lip model
def test_paper_resolution_point_count():
    lip = LipModel("paper")
    assert abs(lip.n_points - 4261) <= 5
    assert abs(3 * lip.n_points - 12784) <= 15


@pytest.mark.parametrize("res, lo, hi", [("small", 100, 300), ("default", 500, 1000)])
def test_resolutions(res, lo, hi):
    lip = LipModel(res)
    assert lo <= lip.n_points <= hi
    assert lip.rest_vertices.shape == (lip.n_points, 3)
    assert np.isfinite(lip.rest_vertices).all()
    assert lip.faces.min() == 0 and lip.faces.max() == lip.n_points - 1
    assert len(lip.point_names) == len(set(lip.point_names)) == lip.n_points
    V, F = lip.rest_vertices, lip.faces
    normals = np.cross(V[F[:, 1]] - V[F[:, 0]], V[F[:, 2]] - V[F[:, 0]])
    assert (normals[:, 2] > 0).mean() > 0.9  # the surface faces forward (+z)


def test_lip_model_rejects_bad_input():
    with pytest.raises(ValueError, match="resolution"):
        LipModel("huge")
    with pytest.raises(ValueError, match="shape"):
        LipModel("small").deform(np.zeros((3, 5)))
    with pytest.raises(ValueError, match="anatomy"):
        LipModel("small", anatomy={"half_width": 20})


def test_deformations_are_physically_sensible():
    lip = LipModel("default")
    rest = lip.deform(_controls()).reshape(-1, 3)
    moves = {k: lip.deform(_controls(**{k: 1.0})).reshape(-1, 3) - rest for k in CONTROL_NAMES}
    size = {k: np.linalg.norm(v) for k, v in moves.items()}
    assert max(size, key=size.get) == "jaw"  # the largest motion
    n = lip.rows * lip.cols
    up, lo = slice(0, n), slice(n, 2 * n)
    assert moves["jaw"][lo, 1].mean() < -5 and abs(moves["jaw"][up, 1].mean()) < 2
    corner = np.argmax(np.abs(rest[:n, 0]) * (np.abs(rest[:n, 0]) < 26))
    assert abs((rest + moves["round"])[corner, 0]) < abs(rest[corner, 0]) - 2   # narrows
    assert abs((rest + moves["spread"])[corner, 0]) > abs(rest[corner, 0]) + 1  # widens
    assert moves["protrude"][:, 2].max() > 3.5                                 # protrudes
    assert moves["round"][:, 2].max() < moves["protrude"][:, 2].max() / 2      # rounding alone barely does
    mid_lo = lip.midline[1]
    assert moves["labiodental"][mid_lo, 2] < -2 and moves["labiodental"][mid_lo, 1] > 0  # up and back
    ap = lip.aperture(np.vstack([_controls(), _controls(jaw=1.0), _controls(closure=1.0),
                                 _controls(jaw=1.0, closure=1.0), _controls(labiodental=1.0)]))
    assert ap[1] > 15 and ap[0] > 1
    assert ap[2] < 0.01 and ap[3] < 0.01  # contact, whatever the jaw does
    assert 0.5 < ap[4] < 4


def test_aperture_is_the_geometric_inner_lip_distance():
    lip = LipModel("small")
    rng = np.random.default_rng(0)
    c = rng.random((50, len(CONTROL_NAMES)))
    signed = [CONTROL_NAMES.index(n) for n in SIGNED_CONTROLS]
    c[:, signed] = 2 * c[:, signed] - 1
    P = lip.deform(c).reshape(50, -1, 3)
    upper, lower = lip.midline
    np.testing.assert_allclose(lip.aperture(c), P[:, upper, 1] - P[:, lower, 1], atol=1e-4)
    assert (lip.aperture(c) >= 0).all()
    # lips never pass through each other anywhere along the contour
    n = lip.rows * lip.cols
    assert (P[:, :lip.cols, 1] - P[:, n:n + lip.cols, 1] >= -1e-4).all()


# -------------------------------------------------------------- the talker
def test_every_phone_has_articulatory_targets():
    assert set(PHONES) <= set(PHONE_GESTURES)
    for gestures in PHONE_GESTURES.values():
        for g in gestures:
            assert len(g.target) == len(CONTROL_NAMES) and all(-1 <= t <= 1 for t in g.target)


def test_small_corpus_shape_and_alignment(small):
    c = small
    assert isinstance(c, Corpus)
    c.validate()
    assert c.rate == 60.0 and c.n_frames == 4500 and 100 <= c.n_points <= 300
    assert c.faces is not None and c.point_names is not None
    assert set(c.latent) == set(CONTROL_NAMES) | {"aperture", "phase"}
    assert all(v.shape == (c.n_frames,) and np.isfinite(v).all() for v in c.latent.values())
    assert c.utterances[0].id == "s0001" and len(c.utterances) >= 10
    for u in c.utterances:
        assert u.phones[0].label == PAUSE and u.phones[-1].label == PAUSE
        assert u.phones[0].start == 0.0
        assert u.phones[-1].end == pytest.approx(u.n_frames / c.rate)
        assert u.text.endswith(".") and len(u.text.split()) >= 1
    assert c.frames.dtype == np.float32


def test_phone_frequencies_are_plausible(small):
    _, labels, *_ = small.phone_table()
    speech = labels[labels != PAUSE]
    assert len(speech) / small.duration > 7  # phones per second of read speech
    present = set(speech)
    assert len(present & set(PAPER_COUNTS)) >= 36
    counts = np.array([(speech == p).sum() for p in PAPER_COUNTS], float)
    assert np.corrcoef(counts, list(PAPER_COUNTS.values()))[0, 1] > 0.8


def test_determinism_and_seed():
    a = SyntheticTalker(preset="small", n_sentences=3, seed=5).generate()
    b = SyntheticTalker(preset="small", n_sentences=3, seed=5).generate()
    np.testing.assert_array_equal(a.frames, b.frames)
    assert [u.phones for u in a.utterances] == [u.phones for u in b.utterances]
    c = SyntheticTalker(preset="small", n_sentences=3, seed=6).generate()
    assert a.utterances[0].text != c.utterances[0].text or not np.array_equal(a.frames[:100], c.frames[:100])
    assert len(a.utterances) == 3


def test_exact_duration_and_resolution_override():
    c = SyntheticTalker(preset="small", duration=10.0, resolution=(4, 7), rate=50.0).generate()
    assert c.n_frames == 500 and c.n_points == 56 and c.rate == 50.0


def test_aperture_closed_for_bilabials_open_for_open_vowels(small):
    mids, labels, *_ = small.phone_table()
    ap = small.latent["aperture"]
    closed = np.median(ap[mids[np.isin(labels, ["p", "b", "m"])]])
    opened = np.median(ap[mids[np.isin(labels, ["aa", "ae"])]])
    assert closed < 1.5 and opened > 6 and opened > 5 * closed


def _velocity(corpus, name):
    x = corpus.latent[name]
    v = np.zeros_like(x)
    for s, e in corpus.bounds:  # central differences inside each utterance
        v[s:e] = np.gradient(x[s:e]) if e - s > 1 else 0.0
    return v


def test_m_closes_while_p_b_open(small):
    """The paper's Fig. 4: /m/ mid-points in the closing phase, /p b/ in the opening one."""
    mids, labels, *_ = small.phone_table()
    v = _velocity(small, "aperture")
    m = v[mids[labels == "m"]]
    pb = v[mids[np.isin(labels, ["p", "b"])]]
    assert len(m) >= 10 and len(pb) >= 10
    assert (m < 0).mean() > 0.65
    assert (pb > 0).mean() > 0.65


def test_first_principal_component_is_jaw_opening(small):
    F = (small.frames - small.frames.mean(0)).astype(np.float64)
    _, S, Vt = np.linalg.svd(F.T @ F)  # (3V, 3V) is small here; same right vectors as SVD of F
    assert S[0] / S.sum() > 0.3
    assert abs(np.corrcoef(F @ Vt[0], small.latent["jaw"])[0, 1]) > 0.8
    # ... and it is lip opening: jaw and lips open and close together, as in real speech
    assert abs(np.corrcoef(F @ Vt[0], small.latent["aperture"])[0, 1]) > 0.98


def test_controls_are_smooth_and_bounded(small):
    for name in CONTROL_NAMES:
        x = small.latent[name]
        assert x.min() >= (-1 if name in SIGNED_CONTROLS else 0) and x.max() <= 1
        # second-order dynamics: frame-to-frame steps inside an utterance are small (sentences
        # are separate recordings: posture may differ from one to the next)
        assert max(np.abs(np.diff(x[s:e])).max() for s, e in small.bounds) < 0.35


def test_progress_and_cancel():
    stages = []
    SyntheticTalker(preset="small", n_sentences=2).generate(progress=lambda s, d, t: stages.append(s))
    assert {"sentences", "articulation", "geometry"} <= set(stages)

    def cancel(stage, done, total):
        if stage == "geometry":
            raise Cancelled

    with pytest.raises(Cancelled):
        SyntheticTalker(preset="small", n_sentences=2).generate(progress=cancel)


def test_bad_parameters_are_rejected():
    with pytest.raises(ValueError, match="preset"):
        SyntheticTalker(preset="huge").generate()
    with pytest.raises(ValueError, match="rate"):
        SyntheticTalker(preset="small", rate=-1.0).generate()
    with pytest.raises(ValueError, match="n_sentences"):
        SyntheticTalker(preset="small", n_sentences=0).generate()
    with pytest.raises(ValueError, match="speakers must be an integer in 1..100"):
        SyntheticTalker(preset="small", speakers=0).generate()
    with pytest.raises(ValueError, match=r"registration must be in \[0, 5\]"):
        SyntheticTalker(preset="small", registration=-0.1).generate()


# ------------------------------------------------------------------ cache
def test_cache_hit_returns_identical_corpus(tmp_cache):
    stages = []
    a = load_synthetic(preset="small", n_sentences=3, progress=lambda s, d, t: stages.append(s))
    files = list(tmp_cache.glob("*.npz"))
    assert len(files) == 1 and "geometry" in stages
    stages.clear()
    b = load_synthetic(preset="small", n_sentences=3, progress=lambda s, d, t: stages.append(s))
    assert "geometry" not in stages  # loaded, not regenerated
    np.testing.assert_array_equal(a.frames, b.frames)
    assert [u.phones for u in a.utterances] == [u.phones for u in b.utterances]
    assert [u.text for u in a.utterances] == [u.text for u in b.utterances]
    for k in a.latent:
        np.testing.assert_array_equal(a.latent[k], b.latent[k])
    np.testing.assert_array_equal(a.faces, b.faces)
    # other parameters, other file
    load_synthetic(preset="small", n_sentences=3, seed=1)
    assert len(list(tmp_cache.glob("*.npz"))) == 2


def test_cache_dir_argument_and_damaged_file(tmp_path, tmp_cache):
    d = tmp_path / "elsewhere"
    a = load_synthetic(preset="small", n_sentences=2, cache_dir=d)
    (f,) = d.glob("*.npz")
    assert not tmp_cache.exists() or not list(tmp_cache.glob("*.npz"))
    f.write_bytes(b"not a corpus")
    b = load_synthetic(preset="small", n_sentences=2, cache_dir=d)  # regenerated
    np.testing.assert_array_equal(a.frames, b.frames)
    assert Corpus.load(f).n_frames == a.n_frames


# ------------------------------------------- the corpus through the engine
def test_manifold_of_the_small_corpus_is_paper_like(small_manifold):
    """Shape component 1 is opening, opening velocity is one of the first three
    embedding axes, and the engine sees /p b/ opening and /m/ closing (Fig. 4)."""
    m = small_manifold
    corpus = m.corpus_
    assert abs(np.corrcoef(m.Fx_[:, 0], corpus.latent["jaw"])[0, 1]) > 0.8
    r_vel = [abs(np.corrcoef(m.Fy_[:, k], m.Fxv_[:, 0])[0, 1]) for k in range(3)]
    assert max(r_vel) > 0.8
    mids, labels, *_ = corpus.phone_table()
    v = m.Fxv_[:, 0]
    assert (v[mids[np.isin(labels, ["p", "b"])]] > 0).mean() > 0.75
    assert (v[mids[labels == "m"]] < 0).mean() > 0.6


def test_generator_variants_leave_the_default_talker_unchanged(tmp_cache):
    """The held-out talker's keyword-only parameters: at their defaults nothing changes (same
    frames, same cache file name); the held-out talker differs in timing and dynamics."""
    from engine.talker.synthetic_talker import _VARIANT_DEFAULTS, HELD_OUT_TALKER

    a = SyntheticTalker(preset="small", n_sentences=3).generate()
    b = SyntheticTalker(preset="small", n_sentences=3, **_VARIANT_DEFAULTS).generate()
    np.testing.assert_array_equal(a.frames, b.frames)
    load_synthetic(preset="small", n_sentences=2)
    load_synthetic(preset="small", n_sentences=2, **_VARIANT_DEFAULTS)
    assert len(list(tmp_cache.glob("synthetic-small-*.npz"))) == 1  # one cache file for both
    h = SyntheticTalker(preset="small", n_sentences=3, **HELD_OUT_TALKER).generate()
    slow = SyntheticTalker(preset="small", n_sentences=3, dynamics_scale=2.0).generate()
    # slower articulators: smaller frame-to-frame steps of the controls, same sentences
    step = lambda c: np.abs(np.diff(c.latent["jaw"])).mean()  # noqa: E731
    assert [u.text for u in slow.utterances] == [u.text for u in a.utterances]
    assert step(slow) < 0.8 * step(a)
    assert [u.text for u in h.utterances] != [u.text for u in a.utterances]
    with pytest.raises(ValueError, match=r"dynamics_scale must be in \[0.25, 4\]"):
        SyntheticTalker(preset="small", dynamics_scale=0.0).generate()
    with pytest.raises(ValueError, match="timing_sd must be in"):
        SyntheticTalker(preset="small", timing_sd=-1.0).generate()


# ------------------------------------------------ the new controls and anatomy
def test_new_controls_move_the_lips_as_named():
    lip = LipModel("default")
    rest = lip.deform(_controls()).reshape(-1, 3)
    n, C = lip.rows * lip.cols, lip.cols
    up_mid, lo_mid = lip.midline
    mv = {k: lip.deform(_controls(**{k: 1.0})).reshape(-1, 3) - rest for k in CONTROL_NAMES}
    # lower-lip depression: the lower lip goes down, the upper lip stays
    assert mv["depress"][lo_mid, 1] < -2 and abs(mv["depress"][up_mid, 1]) < 0.1
    # corners: raise moves the commissure region up, not the midline
    corner = int(np.argmin(np.abs(np.abs(rest[:C, 0]) - lip.anatomy.half_width)))
    assert mv["corner"][corner, 1] > 1.5 and abs(mv["corner"][up_mid, 1]) < 0.05
    # asymmetry: left and right halves differ, the midline aperture does not change
    both = lip.deform(_controls(jaw=0.8, asymmetry=1.0)).reshape(-1, 3) - lip.deform(_controls(jaw=0.8)).reshape(-1, 3)
    assert both[lo_mid + 3, 1] * both[lo_mid - 3, 1] < 0  # one side opens more, the other less
    assert lip.aperture(_controls(jaw=0.8, asymmetry=1.0))[0] == pytest.approx(lip.aperture(_controls(jaw=0.8))[0])
    # lateral jaw: the lower lip shifts sideways, the upper lip does not
    assert mv["jaw_lateral"][n:, 0].mean() > 0.8 and np.abs(mv["jaw_lateral"][:n, 0]).max() < 1e-4


def test_rest_shape_has_cupids_bow_and_philtrum():
    lip = LipModel("paper")
    V = lip.rest_vertices
    R, C = lip.rows, lip.cols
    x = V[:C, 0]
    border = int(np.argmin(np.abs(np.linspace(0, 1, R) ** 1.4 - 0.4)))  # the vermilion border row
    y_border = V[border * C:(border + 1) * C, 1]
    mid = C // 2
    peak = mid + int(np.argmax(y_border[mid:mid + C // 4]))
    assert 3 < x[peak] < 7                                   # Cupid's bow peak beside the midline
    assert y_border[peak] - y_border[mid] > 0.8              # with a notch between the peaks
    z_skin = V[(border + 2) * C:(border + 3) * C, 2]
    col = mid + int(np.argmin(np.abs(x[mid:] - 5.0)))
    assert z_skin[col] - z_skin[mid] > 0.5                   # philtral column stands out of the groove
    w = vermilion_weight(lip.point_names)
    assert w.shape == (lip.n_points,) and w[:C].min() == 1 and w[(R - 1) * C:R * C].max() == 0
    assert vermilion_weight(["UL", "LL"]) is None


def test_speakers_differ_in_anatomy_not_in_topology():
    a = SyntheticTalker(preset="small", n_sentences=4, speakers=2).generate()
    assert [u.speaker for u in a.utterances] == ["spk1", "spk2", "spk1", "spk2"]
    rest = [a.frames[u.start] for u in a.utterances[:2]]
    assert np.abs(rest[0] - rest[1]).max() > 1.0
    an = Anatomy.draw(np.random.default_rng(0))
    assert an != Anatomy() and 15 < an.half_width < 35


def test_gesture_phases_follow_the_exact_aperture(small):
    ph = small.latent["phase"]
    ap = small.latent["aperture"]
    ends = small.bounds[:, 1] - 1
    assert (ph[ends] == -1).all() and set(np.unique(ph)) == {-1, 0, 1, 2, 3}
    ok = np.ones(len(ap), bool)
    ok[ends] = False
    v = np.zeros_like(ap)
    v[:-1] = np.diff(ap)
    assert ((ph[ok] <= 1) == (v[ok] > 0)).all()
    np.testing.assert_array_equal(gesture_phases(ap, small.bounds), ph)
    # opening (faster, then slower), then turning to close: the turn accelerates the closing
    np.testing.assert_array_equal(gesture_phases(np.array([0, 1, 3, 4, 4.5, 4.0]), [[0, 6]]), [1, 0, 1, 1, 2, -1])


def test_look_ahead_rounding_starts_before_the_rounded_vowel():
    """Protrusion anticipates a rounded vowel across the consonants before it."""
    c = SyntheticTalker(preset="small", duration=240.0).generate()
    pro = c.latent["protrude"]
    # consonants /t d s z n l k g/ directly before /uw/ vs before /iy/
    before = {"uw": [], "iy": []}
    for u in c.utterances:
        for a, b in zip(u.phones[:-1], u.phones[1:]):
            if a.label in ("t", "d", "s", "z", "n", "l", "k", "g") and b.label in before:
                before[b.label].append(pro[u.start + int(round(a.mid * c.rate))])
    assert len(before["uw"]) >= 5 and len(before["iy"]) >= 5
    assert np.median(before["uw"]) > np.median(before["iy"]) + 0.2
