"""``lipspace build --dask ADDRESS`` on a running scheduler (issue 13)."""
import numpy as np
import pytest

from app.cli import main

pytest.importorskip("distributed")


def test_build_on_a_running_scheduler(tmp_path, small_corpus, capsys, dask_cluster):
    from engine.manifold import Manifold

    corpus = small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])
    src = corpus.save(tmp_path / "c.npz")
    out = tmp_path / "m.npz"
    assert main(["build", str(src), "-o", str(out), "-q", "--states", "30", "--dask",
                 dask_cluster.scheduler_address, "--dask-blocks", str(tmp_path / "blocks")]) == 0
    text = capsys.readouterr().out
    assert "Dask 2 workers, 2 threads at " + dask_cluster.scheduler_address in text
    assert sorted(p.name for p in (tmp_path / "blocks" / "frames").iterdir())[0] == "block_00000.npy"
    m = Manifold.load(out)
    assert m.Fy_.shape == (corpus.n_frames, 10) and np.isfinite(m.Fy_).all()
