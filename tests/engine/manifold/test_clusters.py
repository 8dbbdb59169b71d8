"""Phone clusters: statistics, ellipses, ellipsoids, separations, and the paper's /m/ vs /p, b/ claim."""
import numpy as np
import pytest
from sklearn.base import clone

from engine.manifold.clusters import PhoneClusters, bhattacharyya, dprime


def _spd(rng, d, scale=1.0):
    A = rng.normal(size=(d, d))
    return scale * (A @ A.T / d + 0.3 * np.eye(d))


@pytest.fixture(scope="module")
def clouds():
    """Three phones as Gaussian clouds with known means / covariances, plus pauses and a rare label.

    /p/ and /m/ share their shape (X) distribution and differ only in the velocity
    dimension of Y; /s/ is far away in both. Frames are shuffled so members interleave.
    """
    rng = np.random.default_rng(0)
    spec = {"p": 900, "m": 700, "s": 500}
    mean_y = {"p": np.array([0.0, 1.0, 2.0, 0.0]), "m": np.array([0.0, 1.0, -2.0, 0.0]),
              "s": np.array([6.0, -3.0, 0.0, 1.0])}
    cov_y = {k: _spd(rng, 4) for k in spec}
    mean_x = {"p": np.array([1.0, 0.0, 0.5]), "m": np.array([1.0, 0.0, 0.5]), "s": np.array([-4.0, 2.0, 0.0])}
    cov_x = {"p": _spd(rng, 3), "s": _spd(rng, 3)}
    cov_x["m"] = cov_x["p"]
    labels, Y, X = [], [], []
    for k, n in spec.items():
        labels += [k] * n
        Y.append(rng.multivariate_normal(mean_y[k], cov_y[k], n))
        X.append(rng.multivariate_normal(mean_x[k], cov_x[k], n))
    labels += ["sil"] * 40 + ["zh"] * 2
    Y.append(rng.normal(size=(42, 4)))
    X.append(rng.normal(size=(42, 3)))
    Y, X, labels = np.vstack(Y), np.vstack(X), np.array(labels)
    # frames in shuffled order, plus filler frames that are no phone's mid-point
    N = len(labels) + 300
    frames = rng.permutation(N)[: len(labels)]
    Fy = rng.normal(size=(N, 5)).astype(np.float32) * 50
    Fx = rng.normal(size=(N, 4)).astype(np.float32) * 50
    Fy[frames, :4] = Y
    Fx[frames, :3] = X
    # signed velocity: the third Y dim (the "velocity" axis here) decides the side
    sv = Fy[:, 2].astype(np.float64)
    return dict(Fy=Fy, Fx=Fx, mids=frames, labels=labels, sv=sv, mean_y=mean_y, cov_y=cov_y,
                mean_x=mean_x, cov_x=cov_x, spec=spec)


@pytest.fixture(scope="module")
def fitted(clouds):
    c = clouds
    return PhoneClusters(n_dims=3).fit(c["Fy"], c["Fx"], c["mids"], c["labels"], signed_velocity=c["sv"])


def test_counts_order_and_exclusions(fitted, clouds):
    assert fitted.phones_ == ["p", "m", "s"]
    assert fitted.counts_.tolist() == [900, 700, 500]
    assert fitted.excluded_phones_ == ["zh"] and fitted.excluded_counts_.tolist() == [2]
    assert fitted.n_pauses_ == 40
    assert fitted.member_offsets_.tolist() == [0, 900, 1600, 2100]
    for ph in fitted.phones_:
        assert np.array_equal(fitted.members(ph), clouds["mids"][clouds["labels"] == ph])
    with pytest.raises(ValueError, match="fewer than min_count=3"):
        fitted.index("zh")
    with pytest.raises(ValueError, match="no cluster for phone 'ng'"):
        fitted.index("ng")
    # pauses kept on request; a lower min_count keeps the rare label
    pc = PhoneClusters(exclude_pauses=False, min_count=2).fit(clouds["Fy"], clouds["Fx"], clouds["mids"],
                                                               clouds["labels"])
    assert pc.phones_ == ["p", "m", "s", "sil", "zh"] and pc.n_pauses_ == 0


def test_means_and_covariances(fitted, clouds):
    c = clouds
    for i, ph in enumerate(fitted.phones_):
        rows = c["mids"][c["labels"] == ph]
        Y = c["Fy"][rows, :3].astype(np.float64)
        X = c["Fx"][rows, :3].astype(np.float64)
        # exactly the sample statistics (ddof=1) of the members ...
        np.testing.assert_allclose(fitted.means_[i], Y.mean(0), rtol=1e-12)
        np.testing.assert_allclose(fitted.covariances_[i], np.cov(Y, rowvar=False), rtol=1e-10)
        np.testing.assert_allclose(fitted.means_x_[i], X.mean(0), rtol=1e-12)
        np.testing.assert_allclose(fitted.covariances_x_[i], np.cov(X, rowvar=False), rtol=1e-10)
        # ... which estimate the generating Gaussians (first n_dims dims of Y)
        n = fitted.counts_[i]
        sd = np.sqrt(np.diag(c["cov_y"][ph][:3, :3]))
        assert np.all(np.abs(fitted.means_[i] - c["mean_y"][ph][:3]) < 4 * sd / np.sqrt(n))
        np.testing.assert_allclose(fitted.covariances_[i], c["cov_y"][ph][:3, :3], atol=0.25 * sd.max() ** 2)
    assert fitted.means_.shape == (3, 3) and fitted.covariances_.shape == (3, 3, 3)
    assert fitted.n_dims_ == 3 and fitted.n_dims_x_ == 3


def test_opening_fraction(fitted, clouds):
    c = clouds
    for i, ph in enumerate(fitted.phones_):
        v = c["sv"][c["mids"][c["labels"] == ph]]
        assert fitted.opening_fraction_[i] == pytest.approx(np.mean(v > 0))
    # /p/ sits on the opening side (mean +2 s.d.-ish), /m/ on the closing side
    assert fitted.opening_fraction_[0] > 0.8 and fitted.opening_fraction_[1] < 0.2
    # a callable on F^y rows gives the same; no velocity gives NaN
    pc = PhoneClusters().fit(c["Fy"], c["Fx"], c["mids"], c["labels"], signed_velocity=lambda Y: Y[:, 2])
    np.testing.assert_allclose(pc.opening_fraction_, fitted.opening_fraction_)
    np.testing.assert_allclose(pc.member_velocity_, c["sv"][pc.members_])
    pc = PhoneClusters().fit(c["Fy"], c["Fx"], c["mids"], c["labels"])
    assert np.all(np.isnan(pc.opening_fraction_)) and pc.member_velocity_ is None


@pytest.mark.parametrize("axes", [(0, 1), (0, 2), (2, 1)])
@pytest.mark.parametrize("space", ["y", "x"])
def test_ellipse_points_are_at_mahalanobis_n_sd(fitted, axes, space):
    i = 1
    mean = (fitted.means_ if space == "y" else fitted.means_x_)[i][list(axes)]
    cov = (fitted.covariances_ if space == "y" else fitted.covariances_x_)[i][np.ix_(axes, axes)]
    for n_sd in (1.0, 2.0):
        pts = fitted.ellipse("m", axes=axes, n_sd=n_sd, n_points=400, space=space)
        assert pts.shape == (400, 2)
        d = pts - mean
        maha = np.sqrt(np.einsum("ij,ij->i", d, np.linalg.solve(cov, d.T).T))
        np.testing.assert_allclose(maha, n_sd, rtol=1e-9)
        # radii: farthest / nearest points are n_sd * sqrt of the eigenvalues
        lam = np.linalg.eigvalsh(cov)
        r = np.linalg.norm(d, axis=1)
        assert r.max() == pytest.approx(n_sd * np.sqrt(lam[1]), rel=1e-3)
        assert r.min() == pytest.approx(n_sd * np.sqrt(lam[0]), rel=1e-3)
    assert len({tuple(p) for p in np.round(pts, 9)}) == 400  # once round, no repeated point


def test_ellipsoid_mesh(fitted):
    mean, cov = fitted.means_[2], fitted.covariances_[2]
    verts, faces = fitted.ellipsoid("s", n_sd=2.0, resolution=60)
    assert verts.shape[1] == 3 and faces.shape[1] == 3 and faces.dtype.kind == "i"
    assert faces.min() == 0 and faces.max() == len(verts) - 1
    d = verts - mean
    maha = np.sqrt(np.einsum("ij,ij->i", d, np.linalg.solve(cov, d.T).T))
    np.testing.assert_allclose(maha, 2.0, rtol=1e-9)
    # closed surface: every edge shared by exactly two triangles
    e = np.sort(np.vstack([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]]), axis=1)
    _, counts = np.unique(e, axis=0, return_counts=True)
    assert set(counts.tolist()) == {2}
    # outward orientation: the signed volume is positive and close to 4/3 pi n_sd^3 sqrt(det)
    a, b, c = (verts[faces[:, k]] - mean for k in range(3))
    vol = np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6
    assert vol == pytest.approx(4 / 3 * np.pi * 8 * np.sqrt(np.linalg.det(cov)), rel=0.01)
    # other axes and the shape space
    v2, f2 = fitted.ellipsoid("s", resolution=8, axes=(0, 2, 1), space="x")
    assert len(f2) < len(faces) and np.all(np.isfinite(v2))
    with pytest.raises(ValueError, match="axes"):
        fitted.ellipsoid("s", axes=(0, 1, 3))
    with pytest.raises(ValueError, match="axes"):
        fitted.ellipse("s", axes=(1, 1))


def test_bhattacharyya_closed_form():
    # 1-D: N(0, 1) vs N(mu, s^2): mu^2 / (4 (1 + s^2)) + 1/2 ln((1 + s^2) / (2 s))
    for mu, s in [(0.0, 1.0), (1.5, 1.0), (2.0, 3.0), (-1.0, 0.5)]:
        want = mu ** 2 / (4 * (1 + s ** 2)) + 0.5 * np.log((1 + s ** 2) / (2 * s))
        got = bhattacharyya(np.zeros(1), np.eye(1), np.array([mu]), np.array([[s ** 2]]))
        assert got == pytest.approx(want, rel=1e-12, abs=1e-15)
    # equal covariances: one eighth of the squared Mahalanobis distance
    rng = np.random.default_rng(1)
    C = _spd(rng, 3)
    a, b = rng.normal(size=3), rng.normal(size=3)
    assert bhattacharyya(a, C, b, C) == pytest.approx((a - b) @ np.linalg.solve(C, a - b) / 8)
    # d' with isotropic spread sigma: |mu_a - mu_b| / sigma
    assert dprime(np.zeros(3), 4 * np.eye(3), np.array([3.0, 4.0, 0.0]), 4 * np.eye(3)) == pytest.approx(2.5)
    assert dprime(a, C, a, C) == 0.0
    # batched shapes
    assert bhattacharyya(np.zeros((2, 5, 3)), np.broadcast_to(C, (2, 5, 3, 3)), np.ones(3), C).shape == (2, 5)


def test_separation_matches_the_gaussian_fits(fitted):
    for sp, (means, covs) in {"y": (fitted.means_, fitted.covariances_),
                              "x": (fitted.means_x_, fitted.covariances_x_)}.items():
        S = fitted.separation_matrix(sp)
        assert S.shape == (3, 3) and np.allclose(S, S.T) and np.all(np.diag(S) == 0)
        for i in range(3):
            for j in range(3):
                if i != j:
                    assert S[i, j] == pytest.approx(bhattacharyya(means[i], covs[i], means[j], covs[j]), rel=1e-6)
        D = fitted.separation_matrix(sp, measure="dprime")
        assert D[0, 1] == pytest.approx(dprime(means[0], covs[0], means[1], covs[1]), rel=1e-6)
    assert fitted.separation("p", "m", "y") == pytest.approx(fitted.separation_matrix("y")[0, 1])
    sub = fitted.separation_matrix("x", phones=["s", "p"])
    assert sub[0, 1] == pytest.approx(fitted.separation_matrix("x")[2, 0])
    with pytest.raises(ValueError, match="space"):
        fitted.separation("p", "m", "z")
    with pytest.raises(ValueError, match="measure"):
        fitted.separation("p", "m", measure="euclid")


def test_dynamics_separate_what_shape_cannot(fitted, clouds):
    """The paper's claim in miniature: /p/ and /m/ share their shapes and differ only in velocity."""
    y, x = fitted.separation("m", "p", "y"), fitted.separation("m", "p", "x")
    print(f"\n/m/ vs /p/ Bhattacharyya: Y {y:.3f}, X {x:.3f}")
    assert y > 1.0 and x < 0.02 and y > 50 * x
    assert fitted.separation("m", "p", "y", measure="dprime") > fitted.separation("m", "p", "x", measure="dprime")
    # /s/ differs in both
    assert fitted.separation("s", "p", "x") > 1.0 and fitted.separation("s", "p", "y") > 1.0


def test_table_rows(fitted):
    rows = fitted.table()
    assert [r["phone"] for r in rows] == fitted.phones_
    r = rows[1]
    assert r["count"] == 700 and r["broad_class"] == "bilabial" and r["lipreading_class"] == "protected"
    assert [r["y1"], r["y2"], r["y3"]] == pytest.approx(fitted.means_[1].tolist())
    assert r["opening_fraction"] == pytest.approx(fitted.opening_fraction_[1])
    Sy, Sx = fitted.separation_matrix("y"), fitted.separation_matrix("x")
    for i, row in enumerate(rows):
        others = [j for j in range(3) if j != i]
        ny = min(others, key=lambda j: Sy[i, j])
        nx = min(others, key=lambda j: Sx[i, j])
        assert row["nearest_y"] == fitted.phones_[ny] and row["separation_y"] == pytest.approx(Sy[i, ny])
        assert row["separation_x"] == pytest.approx(Sx[i, ny])
        assert row["nearest_x"] == fitted.phones_[nx] and row["separation_nearest_x"] == pytest.approx(Sx[i, nx])
    assert rows[2]["broad_class"] == "alveolar"
    assert [r["phone"] for r in fitted.table(["s", "m"])] == ["s", "m"]
    dp = fitted.table(measure="dprime")
    assert dp[0]["separation_x"] == pytest.approx(
        fitted.separation_matrix("x", measure="dprime")[0, fitted.phones_.index(dp[0]["nearest_y"])])


def test_normalized_labels_and_lookup(clouds):
    rng = np.random.default_rng(3)
    N = 60
    Fy, Fx = rng.normal(size=(N, 3)), rng.normal(size=(N, 3))
    labels = ["AH0"] * 5 + ["ax"] * 4 + ["AH1"] * 6 + ["M"] * 5 + ["SIL"] * 3 + ["xyz"] * 4 + ["sp"] * 3
    mids = np.arange(len(labels))
    raw = PhoneClusters().fit(Fy, Fx, mids, labels)
    assert raw.phones_ == ["AH1", "AH0", "M", "ax", "xyz"] and raw.n_pauses_ == 6 and raw.phoneset_ == "arpabet"
    assert raw.index("m") == raw.phones_.index("M")  # looked up through the phone-set table
    assert raw.table(["M"])[0]["lipreading_class"] == "protected"
    assert raw.table(["xyz"])[0]["broad_class"] == "unknown"
    norm = PhoneClusters(normalize_labels=True).fit(Fy, Fx, mids, labels)
    assert norm.phones_ == ["ax", "ah", "m", "xyz"] and norm.counts_.tolist() == [9, 6, 5, 4]
    np.testing.assert_allclose(norm.means_[0], Fy[:9].mean(0))


def test_input_validation(clouds):
    c = clouds
    args = (c["Fy"], c["Fx"], c["mids"], c["labels"])
    with pytest.raises(ValueError, match="n_dims=6 but F\\^y has 5"):
        PhoneClusters(n_dims=6).fit(*args)
    with pytest.raises(ValueError, match="min_count must be an integer >= 2, got 1"):
        PhoneClusters(min_count=1).fit(*args)
    with pytest.raises(ValueError, match="outside the"):
        PhoneClusters().fit(c["Fy"], c["Fx"], np.r_[c["mids"][:-1], len(c["Fy"])], c["labels"])
    with pytest.raises(ValueError, match="labels for"):
        PhoneClusters().fit(c["Fy"], c["Fx"], c["mids"], c["labels"][:-1])
    with pytest.raises(ValueError, match="Fx has"):
        PhoneClusters().fit(c["Fy"], c["Fx"][:-1], c["mids"], c["labels"])
    with pytest.raises(ValueError, match="signed_velocity has shape"):
        PhoneClusters().fit(*args, signed_velocity=np.zeros(3))
    Fy = c["Fy"].copy()
    Fy[c["mids"][5], 1] = np.nan
    with pytest.raises(ValueError, match=f"row {c['mids'][5]} .* not finite"):
        PhoneClusters().fit(Fy, c["Fx"], c["mids"], c["labels"])
    with pytest.raises(TypeError, match="fit\\(manifold\\)"):
        PhoneClusters().fit(c["Fy"])
    # fewer shape components than n_dims: X uses what there is
    pc = PhoneClusters(n_dims=3).fit(c["Fy"], c["Fx"][:, :2], c["mids"], c["labels"])
    assert pc.n_dims_x_ == 2 and pc.means_x_.shape == (3, 2)


def test_estimator_api_and_persistence(fitted):
    from engine.files.persist import dump_estimator, load_estimator

    assert clone(fitted).get_params() == fitted.get_params()
    d = dump_estimator(fitted, "clusters")
    back = load_estimator(PhoneClusters, d, "clusters")
    assert back.phones_ == fitted.phones_ and back.excluded_phones_ == fitted.excluded_phones_
    np.testing.assert_array_equal(back.covariances_, fitted.covariances_)
    assert back.separation("m", "p", "y") == pytest.approx(fitted.separation("m", "p", "y"))


# ---------------------------------------------------------------- the synthetic talker
#: the engine's opening side must agree with the talker's true opening velocity this often
#: (measured: 0.817 on the small preset of generator 4, whose capture noise makes the sign of
#: slow movements uncertain; 0.941 on generator 3, which had almost none)
MIN_SIGN_AGREEMENT = 0.78


def test_bilabials_on_the_synthetic_manifold(small_manifold):
    """Recovery check of a *planted* effect (paper section 5): the synthetic talker is built so that
    /m/'s closure peaks late in the phone (its mid-point lies in the closing phase) and /p b/'s early
    (mid-points in the opening phase). The test checks that the engine recovers what was planted:
    /m/ on the closing side, /p b/ on the opening side; /p/ and /b/ overlap; dynamics pull /m/ away
    from /p/. It is no evidence about real lips; the engine's opening side must also stay within
    3 points of the trivial rule (the sign of the captured lips' own aperture change)."""
    from engine.manifold.local_gradients import central_difference
    from engine.recordings.kinematics import lip_aperture

    m = small_manifold
    corpus = m.corpus_
    pc = PhoneClusters.from_manifold(m)
    mids, labels = corpus.phone_table()[:2]
    assert pc.counts_[pc.index("m")] == np.sum(labels == "m")
    of = {ph: pc.opening_fraction_[pc.index(ph)] for ph in "mpb"}
    B = {(a, b, s): pc.separation(a, b, s) for a, b in [("m", "p"), ("m", "b"), ("p", "b")] for s in "yx"}
    D = {(a, b, s): pc.separation(a, b, s, measure="dprime") for a, b in [("m", "p"), ("p", "b")] for s in "yx"}
    B2 = {s: PhoneClusters(n_dims=2).fit(m).separation("m", "p", s) for s in "yx"}
    # ground truth: the talker's true lip aperture velocity
    true_v = central_difference(corpus.latent["aperture"], corpus.bounds)
    truth = PhoneClusters().fit(m.Fy_, m.Fx_, mids, labels, signed_velocity=true_v)
    true_of = {ph: truth.opening_fraction_[truth.index(ph)] for ph in "mpb"}
    moving = true_v != 0
    agree = float(np.mean((m.tangent_.velocity_[moving] > 0) == (true_v[moving] > 0)))
    print("\nopening fraction (engine) " + ", ".join(f"/{k}/ {v:.3f}" for k, v in of.items()))
    print("opening fraction (true aperture velocity) " + ", ".join(f"/{k}/ {v:.3f}" for k, v in true_of.items()))
    print(f"engine opening side agrees with the true velocity sign on {agree:.3f} of frames")
    print("Bhattacharyya (3 dims) " + ", ".join(f"{a}-{b} {s.upper()} {v:.3f}" for (a, b, s), v in B.items()))
    print("d' (3 dims) " + ", ".join(f"{a}-{b} {s.upper()} {v:.3f}" for (a, b, s), v in D.items()))
    print(f"Bhattacharyya (2 dims) m-p Y {B2['y']:.3f} X {B2['x']:.3f}")

    # the talker itself: /m/ mid-points close, /p b/ mid-points open (as the paper's Fig. 4)
    assert true_of["m"] < 0.5 < min(true_of["p"], true_of["b"])
    # /p/ and /b/ overlap: closer to each other than either is to /m/ in Y, where the dynamics
    # are. (In X the three are all near-closed lips: measured on generator 4, p-b 0.37 vs m-b
    # 0.27, so the static shape alone does not group them; generator 3 did, with less noise.)
    assert B[("p", "b", "y")] < min(B[("m", "p", "y")], B[("m", "b", "y")])
    # the generic fit path gives the same clusters
    pc3 = PhoneClusters().fit(m.Fy_, m.Fx_, mids, labels, signed_velocity=m.tangent_.velocity_)
    np.testing.assert_allclose(pc3.opening_fraction_, pc.opening_fraction_)
    np.testing.assert_allclose(pc3.covariances_, pc.covariances_)

    rule = central_difference(lip_aperture(corpus), corpus.bounds)
    agree_rule = float(np.mean((rule[moving] > 0) == (true_v[moving] > 0)))
    msg = (f"the manifold's opening velocity matches the true opening-velocity sign on {agree:.3f} of frames "
           f"(required {MIN_SIGN_AGREEMENT}); the captured aperture's own change on {agree_rule:.3f} "
           f"(margin {100 * (agree - agree_rule):+.1f} points)")
    print(msg)
    assert agree >= MIN_SIGN_AGREEMENT, msg
    assert agree >= agree_rule - 0.03, msg
    # the engine sees it: /m/ mostly closing, /p/ and /b/ mostly opening
    assert of["m"] < of["p"] and of["m"] < of["b"]
    # dynamics separate /m/ from /p/: centre distance over spread grows from X to Y
    assert D[("m", "p", "y")] > D[("m", "p", "x")]
