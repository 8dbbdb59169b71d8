"""A corpus stored in blocks of frames: written by import, read by build, read in place by Dask workers (issue 13)."""
import numpy as np
import pytest

from app.cli import main
from engine.corpus import Corpus, CorpusError
from engine.corpus_blocks import blocks_folder, is_blocked, load_blocked, save_blocked


@pytest.fixture(scope="module")
def corpus(small_corpus):
    return small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])


def test_round_trip_and_faults_name_the_block(corpus, tmp_path):
    path = tmp_path / "c.npz"
    paths = save_blocked(corpus, path, block_frames=512)
    assert [p.name for p in paths] == [f"block_{i:05d}.npy" for i in range(len(paths))] and len(paths) >= 2
    assert is_blocked(path) and not is_blocked(corpus.save(tmp_path / "whole.npz"))
    back, got = load_blocked(path)
    assert got == paths
    np.testing.assert_array_equal(back.frames, corpus.frames.astype(np.float32))
    np.testing.assert_array_equal(back.bounds, corpus.bounds)
    assert [u.id for u in back.utterances] == [u.id for u in corpus.utterances]
    np.save(paths[1], np.zeros((3, corpus.frames.shape[1]), np.float32))
    with pytest.raises(CorpusError, match=rf"{paths[1].name}: expected a float32 block of shape \(\d+, "):
        load_blocked(path)
    paths[1].unlink()
    with pytest.raises(CorpusError, match=rf"{paths[1].name}: block file missing"):
        load_blocked(path)
    with pytest.raises(ValueError, match="block_frames must be an integer >= 256"):
        save_blocked(corpus, path, block_frames=10)


def test_import_in_blocks_then_build_on_dask_reads_them_in_place(corpus, tmp_path, capsys, dask_cluster):
    from engine.manifold import Manifold

    src = corpus.save(tmp_path / "whole.npz")
    blocked = tmp_path / "c.npz"
    assert main(["import", str(src), "-o", str(blocked), "--block-frames", "512", "--register", "none"]) == 0
    assert "blocks in" in capsys.readouterr().err
    n_blocks = len(list(blocks_folder(blocked).glob("block_*.npy")))
    assert n_blocks >= 2
    out, scratch = tmp_path / "m.npz", tmp_path / "scratch"
    assert main(["build", str(blocked), "-o", str(out), "-q", "--states", "30", "--dask",
                 dask_cluster.scheduler_address, "--dask-blocks", str(scratch)]) == 0
    assert not (scratch / "frames").exists()  # F was not written out again: the workers read the import's blocks
    assert main(["build", str(blocked), "-o", str(tmp_path / "m2.npz"), "-q", "--states", "30"]) == 0  # in-process
    d, ref = Manifold.load(out), Manifold.load(tmp_path / "m2.npz")
    np.testing.assert_array_equal(ref.corpus_.frames, Corpus.load(src).frames)  # the blocks hold the corpus
    assert d.Fx_.shape == ref.Fx_.shape
    from scipy.linalg import subspace_angles

    assert np.degrees(subspace_angles(d.Fx_.astype(np.float64), ref.Fx_.astype(np.float64)).max()) < 0.01
