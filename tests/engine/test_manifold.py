import numpy as np
import pytest
import scipy.sparse as sp

from engine.manifold import Manifold, ManifoldFileError
from engine.progress import Cancelled


def _assert_same_estimator(a, b):
    assert a.get_params() == b.get_params()
    names = [k for k in vars(a) if k.endswith("_") and not k.startswith("_")]
    assert names, type(a)
    for k in names:
        x, y = getattr(a, k), getattr(b, k)
        if sp.issparse(x):
            assert (x != y).nnz == 0, k
        elif isinstance(x, np.ndarray):
            np.testing.assert_array_equal(x, y, err_msg=k)
        else:
            assert x == y, k


def test_save_load_round_trips_exactly(small_manifold, tmp_path):
    path = small_manifold.save(tmp_path / "m.npz")
    m = Manifold.load(path)
    for attr in ("Fx_", "Fxv_", "G_", "Fy_"):
        np.testing.assert_array_equal(getattr(m, attr), getattr(small_manifold, attr))
    for part in ("shape_", "dynamics_", "embedding_", "tangent_", "states_"):
        _assert_same_estimator(getattr(small_manifold, part), getattr(m, part))
    np.testing.assert_array_equal(m.corpus_.frames, small_manifold.corpus_.frames)
    assert m.corpus_.utterances == small_manifold.corpus_.utterances
    assert m.get_params() == small_manifold.get_params()
    # the loaded object works without refitting
    np.testing.assert_allclose(m.embedding_.transform(m.G_[:20]), m.Fy_[:20], atol=1e-3 * np.abs(m.Fy_).max())
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.npz"]


def test_save_without_frames_reconstructs(small_manifold, tmp_path):
    path = small_manifold.save(tmp_path / "m.npz", include_frames=False)
    m = Manifold.load(path)
    expected = small_manifold.shape_.inverse_transform(small_manifold.Fx_)
    np.testing.assert_allclose(m.corpus_.frames, expected, rtol=0, atol=1e-5)


def test_project_training_frames_reproduces_fy(small_manifold):
    c = small_manifold.corpus_
    u = c.utterances[1]
    Y = small_manifold.project(c.frames[u.start:u.stop])
    ref = small_manifold.Fy_[u.start:u.stop]
    assert np.abs(Y - ref).max() / np.abs(small_manifold.Fy_).max() < 1e-3


def test_load_errors_name_the_file(tmp_path, small_corpus):
    with pytest.raises(ManifoldFileError, match="no such"):
        Manifold.load(tmp_path / "missing.npz")
    (tmp_path / "junk.npz").write_bytes(b"not a zip")
    with pytest.raises(ManifoldFileError, match="junk.npz"):
        Manifold.load(tmp_path / "junk.npz")
    small_corpus.save(tmp_path / "corpus.npz")
    with pytest.raises(ManifoldFileError, match="corpus file"):
        Manifold.load(tmp_path / "corpus.npz")


def test_fit_can_be_cancelled(small_corpus):
    calls = []

    def progress(stage, done, total):
        calls.append(stage)
        if stage == "embedding":
            raise Cancelled()

    m = Manifold()
    with pytest.raises(Cancelled):
        m.fit(small_corpus, progress=progress)
    assert "shape space" in calls and not hasattr(m, "Fy_")


@pytest.mark.parametrize("content", [b"", b"PK\x03\x04 truncated zip", bytes(range(256)) * 4],
                         ids=["empty", "truncated-zip", "random-bytes"])
def test_damaged_files_give_the_documented_errors(tmp_path, small_manifold, content):
    from app.cli import main
    from engine.corpus import Corpus, CorpusError

    bad = tmp_path / "damaged.npz"
    bad.write_bytes(content)
    with pytest.raises(ManifoldFileError, match=r"damaged.npz: not a readable .npz manifold file"):
        Manifold.load(bad)
    with pytest.raises(CorpusError, match="damaged.npz: cannot read as a Lipspace corpus"):
        Corpus.load(bad)
    # a half-written manifold (the first bytes of a real one) is refused the same way
    good = small_manifold.save(tmp_path / "good.npz")
    half = tmp_path / "half.npz"
    half.write_bytes(good.read_bytes()[: good.stat().st_size // 2])
    with pytest.raises(ManifoldFileError, match="half.npz"):
        Manifold.load(half)
    assert main(["info", str(bad)]) == 2
