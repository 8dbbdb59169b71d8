import numpy as np
import pytest

from engine.manifold.embedding import Embedding, pairwise_distance_block


@pytest.fixture(scope="module")
def G():
    rng = np.random.default_rng(3)
    t = np.linspace(0, 12 * np.pi, 700)
    X = np.c_[np.cos(t), np.sin(t), 0.3 * np.cos(3 * t), 0.1 * rng.standard_normal(700)]
    return (X @ rng.standard_normal((4, 8))).astype(np.float32)


def _match(A, B, k):
    """Max error of columns of A against B up to sign, relative to B's scale."""
    return max(min(np.abs(A[:, i] - B[:, i]).max(), np.abs(A[:, i] + B[:, i]).max()) / np.abs(B[:, i]).max()
               for i in range(k))


def test_blockwise_pca_of_d_matches_dense(G):
    e = Embedding(n_components=6, method="pca").fit(G)
    D = pairwise_distance_block(G, G).astype(np.float64)
    Dc = D - D.mean(axis=0)
    U, S, _ = np.linalg.svd(Dc, full_matrices=False)
    assert _match(e.embedding_, U[:, :6] * S[:6], 3) < 1e-3
    ratio = S**2 / (S**2).sum()
    np.testing.assert_allclose(e.explained_variance_ratio_[:3], ratio[:3], rtol=1e-3)
    print(f"first 3 dims of Y hold {100 * e.recovered_ratio_[2]:.1f}% of the recovered variance")


def test_mds_matches_dense(G):
    e = Embedding(n_components=4, method="mds").fit(G)
    D2 = pairwise_distance_block(G, G, squared=True).astype(np.float64)
    N = len(G)
    J = np.eye(N) - 1.0 / N
    w, V = np.linalg.eigh(-0.5 * J @ D2 @ J)
    o = np.argsort(w)[::-1][:4]
    assert _match(e.embedding_, V[:, o] * np.sqrt(w[o]), 4) < 1e-3


@pytest.mark.parametrize("method", ["pca", "mds"])
@pytest.mark.parametrize("landmarks", [None, 250])
def test_out_of_sample_reproduces_training(G, method, landmarks):
    e = Embedding(n_components=5, method=method, n_landmarks=landmarks).fit(G)
    Y = e.transform(G[::7])
    scale = np.abs(e.embedding_).max()
    assert np.abs(Y - e.embedding_[::7]).max() / scale < 1e-3


def test_landmark_embedding_agrees_with_full(G):
    full = Embedding(n_components=3).fit(G).embedding_
    lm = Embedding(n_components=3, n_landmarks=350).fit(G).embedding_
    for i in range(2):
        assert abs(np.corrcoef(full[:, i], lm[:, i])[0, 1]) > 0.95


def test_embedding_validates(G):
    with pytest.raises(ValueError, match="method must be"):
        Embedding(method="isomap").fit(G)
    with pytest.raises(ValueError, match="n_components"):
        Embedding(n_components=len(G)).fit(G)
    with pytest.raises(ValueError, match="n_landmarks"):
        Embedding(n_components=5, n_landmarks=3).fit(G)
