"""The cheaper build settings (issue 13 item 5) give the results of the previous, costlier path.

Shape space: the range finder stops iterating once an iteration no longer moves the kept
components (``tol``) instead of always running three. Embedding: one power iteration
instead of two, and 8 MiB blocks of D instead of 96 MiB. Compared against the previous
path (same random numbers): the kept shape components (same count, subspace angles) and
Y1..3 (|corr| per dimension).
"""
from __future__ import annotations

import numpy as np
import pytest
from scipy.linalg import subspace_angles

from engine.manifold.shape import ShapeSpace


def _same_kept_components(new, old, max_degrees):
    assert new.n_components_ == old.n_components_
    m = new.n_components_
    angles = np.degrees(subspace_angles(new.components_.T.astype(np.float64), old.components_.T.astype(np.float64)))
    assert angles.max() < max_degrees, f"kept subspaces differ by {angles.max():.4f} degrees"
    for i in range(min(3, m)):  # the leading components one by one, same orientation
        assert float(new.components_[i] @ old.components_[i]) > 0.9999
    np.testing.assert_allclose(new.explained_variance_, old.explained_variance_, rtol=1e-3)


def test_early_stop_keeps_the_shape_components_of_three_iterations():
    # a clear spectrum (12 directions over noise): one iteration is enough, and is all it does
    rng = np.random.default_rng(1)
    N, C, r = 3000, 400, 12
    F = (rng.standard_normal((N, r)) * np.geomspace(10, 1, r)) @ rng.standard_normal((r, C))
    F = (F + 0.02 * rng.standard_normal((N, C))).astype(np.float32)
    new, old = ShapeSpace().fit(F), ShapeSpace(tol=None).fit(F)
    assert old.n_iter_ == 3 and new.n_iter_ < 3
    _same_kept_components(new, old, max_degrees=2 * new.tol)


def test_talker_keeps_iterating_while_the_kept_count_moves(small_corpus):
    # the small talker's tail moves the kept count (24 after one iteration, 26 after three):
    # the early stop must not take the cheaper, different answer
    F = small_corpus.frames
    new, old = ShapeSpace().fit(F), ShapeSpace(tol=None).fit(F)
    assert ShapeSpace(n_iter=1, tol=None).fit(F).n_components_ != old.n_components_  # the trap is real
    _same_kept_components(new, old, max_degrees=2 * new.tol)


def test_tol_is_validated():
    with pytest.raises(ValueError, match="tol must be >= 0"):
        ShapeSpace(tol=-1).fit(np.ones((5, 3), np.float32))


def test_smaller_blocks_of_D_give_the_same_embedding(small_manifold, monkeypatch):
    import engine.manifold.embedding as emb_mod
    from engine.manifold.embedding import Embedding

    G = small_manifold.G_
    assert emb_mod._BLOCK_BYTES // (4 * G.shape[0]) < G.shape[0] // 4  # several blocks now
    new = Embedding().fit(G)
    monkeypatch.setattr(emb_mod, "_BLOCK_BYTES", 96 * 2**20)  # the previous size: one block here
    old = Embedding().fit(G)
    assert new.n_passes_ == old.n_passes_
    for i in range(3):
        c = abs(np.corrcoef(new.embedding_[:, i], old.embedding_[:, i])[0, 1])
        assert c > 1 - 1e-6, f"Y{i + 1}: |corr| {c}"
    np.testing.assert_allclose(new.embedding_, old.embedding_, rtol=1e-3, atol=1e-4 * np.abs(old.embedding_).max())


def test_non_finite_frame_found_in_a_later_block_is_named():
    F = np.zeros((50, 6), np.float32)
    F[37, 2] = np.nan
    with pytest.raises(ValueError, match="frame 37 holds NaN or inf"):
        ShapeSpace(block_size=16).fit(F)  # the check runs block by block: frame 37 is in the third block
