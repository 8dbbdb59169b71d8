"""``lipspace build --dask ADDRESS`` on a running scheduler (issue 13)."""
import numpy as np
import pytest

from app.cli import main

pytest.importorskip("distributed")


def test_build_on_a_running_scheduler(tmp_path, small_corpus, capsys, dask_cluster):
    from engine.manifold.model import Manifold

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])
    src = corpus.save(tmp_path / "c.npz")
    out = tmp_path / "m.npz"
    assert main(["build", str(src), "-o", str(out), "-q", "--states", "30", "--dask",
                 dask_cluster.scheduler_address, "--dask-blocks", str(tmp_path / "blocks")]) == 0
    text = capsys.readouterr().out
    assert "Dask 2 workers, 2 threads at " + dask_cluster.scheduler_address in text
    assert sorted(p.name for p in (tmp_path / "blocks" / "frames").iterdir())[0] == "block_00000.npy"
    m = Manifold.load(out)
    assert m.Fy_.shape == (corpus.n_frames, 16) and np.isfinite(m.Fy_).all()


def test_manifold_of_a_blocked_corpus_reads_its_frames_from_it(tmp_path, small_corpus, capsys):
    """build writes no copy of a blocked corpus's frames; synthesize reads them from the corpus's blocks, and
    says which file is missing when the corpus is gone (exit 2)."""
    from engine.files.persist import read_npz
    from engine.recordings.corpus_blocks import save_blocked

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])
    src = tmp_path / "c.npz"
    save_blocked(corpus, src, block_frames=512)
    out = tmp_path / "m.npz"
    assert main(["build", str(src), "-o", str(out), "-q", "--states", "30"]) == 0
    assert "corpus_frames" not in read_npz(out, keys_only=True)
    traj = tmp_path / "t.npy"
    uid = corpus.utterances[0].id
    assert main(["synthesize", "--utterance", uid, "--manifold", str(out), "-o", str(traj), "-q"]) == 0
    got = np.load(traj)
    assert got.shape[1] == corpus.frames.shape[1] and np.isfinite(got).all()
    capsys.readouterr()
    src.unlink()
    assert main(["synthesize", "--utterance", uid, "--manifold", str(out), "-o", str(traj), "-q", "--force"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "c.npz" in err[0] and "which is missing" in err[0], err


def test_info_reads_a_corpus_stored_in_blocks(tmp_path, small_corpus, capsys):
    from engine.recordings.corpus_blocks import save_blocked

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])
    save_blocked(corpus, tmp_path / "c.npz", block_frames=512)
    assert main(["info", str(tmp_path / "c.npz")]) == 0
    out = capsys.readouterr().out
    assert "Lipspace corpus" in out and f"frames      {corpus.n_frames} at 60 Hz" in out
