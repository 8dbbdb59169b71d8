"""A corpus stored in blocks of frames: written by import, read by build, read in place by Dask workers (issue 13)."""
import numpy as np
import pytest

from app.cli import main
from engine.recordings.corpus import CorpusError
from engine.recordings.corpus_blocks import blocks_folder, is_blocked, load_blocked, save_blocked


@pytest.fixture(scope="module")
def corpus(small_corpus):
    return small_corpus.subset([u.id for u in small_corpus.utterances if u.stop <= 1500])


def test_round_trip_and_faults_name_the_block(corpus, tmp_path):
    path = tmp_path / "c.npz"
    paths = save_blocked(corpus, path, block_frames=512)
    assert [p.name for p in paths] == [f"block_{i:05d}.npy" for i in range(len(paths))] and len(paths) >= 2
    assert is_blocked(path) and not is_blocked(corpus.save(tmp_path / "whole.npz"))
    back = load_blocked(path)
    assert back.frames.paths == tuple(str(p) for p in paths)  # the block files, in frame order
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


# ---------------------------------------------------------------- lazy frames (the client never gathers F)
@pytest.fixture(scope="module")
def two_speakers(corpus):
    """The corpus with its utterances spoken alternately by two speakers, one of them shifted and
    scaled, so that per-speaker normalisation changes the frames."""
    from dataclasses import replace

    utts = [replace(u, speaker="ab"[k % 2]) for k, u in enumerate(corpus.utterances)]
    F = corpus.frames.astype(np.float64)
    for u in utts[1::2]:
        F[u.start:u.stop] = 1.3 * F[u.start:u.stop] + 0.7
    assert corpus.role_points("upper_lip").size and corpus.role_points("lower_lip").size  # the talker names them
    return replace(corpus, frames=F.astype(np.float32), utterances=utts)


@pytest.fixture(scope="module")
def blocked_two_speakers(two_speakers, tmp_path_factory):
    path = tmp_path_factory.mktemp("blocked") / "two.npz"
    save_blocked(two_speakers, path, block_frames=256)
    return path


@pytest.fixture(scope="module")
def whole_and_blocked_builds(two_speakers, blocked_two_speakers):
    """In-process builds of the same corpus held whole and read from its blocks (windows of 300 rows,
    so that windows straddle the 256-row block files), the blocked one refusing to gather F."""
    import engine.recordings.frame_blocks as fb
    from engine.manifold.model import Manifold
    from engine.recordings.frame_blocks import BlockFrames

    mp = pytest.MonkeyPatch()
    mp.setattr(fb, "WINDOW_ROWS", 300)

    def refuse(self, *args, **kwargs):
        raise AssertionError("the build gathered the blocked frames into one array")

    params = dict(n_states=30, speaker_normalisation="mean+scale")
    try:
        whole = Manifold(**params).fit(two_speakers)
        lazy = load_blocked(blocked_two_speakers)
        assert isinstance(lazy.frames, BlockFrames)
        mp.setattr(BlockFrames, "__array__", refuse)
        mp.setattr(BlockFrames, "astype", refuse)
        blocked = Manifold(**params).fit(lazy)
    finally:
        mp.undo()
    return whole, blocked


def test_block_frames_read_like_the_array(two_speakers, blocked_two_speakers):
    lazy = load_blocked(blocked_two_speakers)
    F, L = two_speakers.frames, lazy.frames
    assert L.shape == F.shape and len(L.paths) == len(L.block_bounds) >= 5
    np.testing.assert_array_equal(L[250:530], F[250:530])  # across a block edge
    np.testing.assert_array_equal(L[-1], F[-1])
    idx = np.array([1300, 3, 257, 3, 900])
    np.testing.assert_array_equal(L[idx], F[idx])  # any order, repeats
    np.testing.assert_array_equal(L[idx, 5], F[idx, 5])
    np.testing.assert_array_equal(L[10:200:7], F[10:200:7])
    np.testing.assert_allclose(L.mean(axis=0), F.mean(axis=0, dtype=np.float64), rtol=1e-6, atol=1e-6)
    with pytest.raises(IndexError, match="out of range"):
        L[F.shape[0]]


def test_in_process_build_on_blocks_equals_build_on_the_whole_corpus(whole_and_blocked_builds):
    from engine.recordings.frame_blocks import BlockFrames

    whole, blocked = whole_and_blocked_builds
    assert isinstance(blocked.corpus_.frames, BlockFrames) and blocked.corpus_.frames.normalisation is not None
    assert "speaker normalisation mean+scale over 2 speakers" in blocked.corpus_.history[-1]
    np.testing.assert_array_equal(np.asarray(blocked.corpus_.frames), whole.corpus_.frames)  # same normalisation
    for attr in ("Fx_", "Fxv_", "G_", "Fy_"):
        np.testing.assert_array_equal(getattr(blocked, attr), getattr(whole, attr), err_msg=attr)
    np.testing.assert_array_equal(blocked.shape_.components_, whole.shape_.components_)
    np.testing.assert_array_equal(blocked.tangent_.opening_, whole.tangent_.opening_)
    np.testing.assert_array_equal(blocked.tangent_.classes_, whole.tangent_.classes_)
    np.testing.assert_array_equal(blocked.states_.labels_, whole.states_.labels_)


def test_manifold_file_references_the_blocked_corpus(whole_and_blocked_builds, blocked_two_speakers, tmp_path):
    import shutil

    from engine.files.persist import read_npz
    from engine.manifold.model import Manifold, ManifoldFileError
    from engine.recordings.frame_blocks import BlockFrames

    whole, blocked = whole_and_blocked_builds
    # the corpus and the manifold side by side in a folder of their own, as a user would keep them
    work = tmp_path / "work"
    work.mkdir()
    shutil.copy(blocked_two_speakers, work / "two.npz")
    shutil.copytree(blocks_folder(blocked_two_speakers), blocks_folder(work / "two.npz"))
    lazy = load_blocked(work / "two.npz")
    m = Manifold(n_states=30, speaker_normalisation="mean+scale").fit(lazy)
    m.save(work / "m.npz")
    keys = read_npz(work / "m.npz", keys_only=True)
    assert "corpus_frames" not in keys and "corpus_blocks_source" in keys
    back = Manifold.load(work / "m.npz")
    assert isinstance(back.corpus_.frames, BlockFrames)
    np.testing.assert_array_equal(np.asarray(back.corpus_.frames), whole.corpus_.frames)  # normalised, as built
    np.testing.assert_array_equal(back.Fy_, blocked.Fy_)

    moved = tmp_path / "moved"  # both moved together: found through the relative path
    shutil.move(work, moved)
    np.testing.assert_array_equal(Manifold.load(moved / "m.npz").corpus_.frames[7], whole.corpus_.frames[7])
    (moved / "two.npz").unlink()  # the corpus gone: the error names it and says what to do
    with pytest.raises(ManifoldFileError, match=r"m\.npz: the frames of this manifold are in the blocked corpus "
                                                r".*two\.npz .*which is missing; put the corpus back"):
        Manifold.load(moved / "m.npz")


def test_import_in_blocks_then_build_on_dask_reads_them_in_place(two_speakers, whole_and_blocked_builds, tmp_path,
                                                                 capsys, dask_cluster):
    """import --block-frames, then build --dask: the workers read the import's blocks (normalised per speaker
    inside their tasks), nothing is written out again, and the result matches the in-process build."""
    from scipy.linalg import subspace_angles

    from engine.manifold.model import Manifold
    from engine.recordings.frame_blocks import BlockFrames

    whole, _ = whole_and_blocked_builds
    src = two_speakers.save(tmp_path / "whole.npz")
    blocked = tmp_path / "c.npz"
    assert main(["import", str(src), "-o", str(blocked), "--block-frames", "512", "--register", "none"]) == 0
    assert "blocks in" in capsys.readouterr().err
    assert len(list(blocks_folder(blocked).glob("block_*.npy"))) >= 2
    out, scratch = tmp_path / "m.npz", tmp_path / "scratch"
    assert main(["build", str(blocked), "-o", str(out), "-q", "--states", "30", "--speaker-norm", "mean+scale",
                 "--dask", dask_cluster.scheduler_address, "--dask-blocks", str(scratch)]) == 0
    assert not (scratch / "frames").exists()  # F was not written out again: the workers read the import's blocks
    d = Manifold.load(out)
    assert isinstance(d.corpus_.frames, BlockFrames)  # the manifold file references the blocked corpus
    np.testing.assert_allclose(np.asarray(d.corpus_.frames), whole.corpus_.frames, rtol=1e-5, atol=1e-4)
    for a, b in ((d.Fx_, whole.Fx_), (d.Fy_[:, :3], whole.Fy_[:, :3])):
        assert np.degrees(subspace_angles(a.astype(np.float64), b.astype(np.float64)).max()) < 0.01
    assert np.mean(d.tangent_.opening_ == whole.tangent_.opening_) > 0.99


def test_dask_block_tasks_normalise_and_measure_the_aperture_as_in_process(two_speakers, blocked_two_speakers,
                                                                          dask_cluster):
    """Per-block tasks on the workers: the speaker sums (reduced on the client) and the lip aperture."""
    from distributed import Client

    from engine.recordings.kinematics import lip_aperture
    from engine.recordings.registration import normalise_speakers
    from engine.scale.executor import DaskExecutor

    lazy = load_blocked(blocked_two_speakers)
    whole = normalise_speakers(two_speakers, mode="mean+scale")
    with DaskExecutor(Client(dask_cluster), block_frames=512) as ex:
        normed = normalise_speakers(lazy, mode="mean+scale", executor=ex)
        np.testing.assert_allclose(np.asarray(normed.frames), whole.frames, rtol=1e-6, atol=1e-5)
        got = lip_aperture(normed, executor=ex)
    ref = lip_aperture(whole)
    assert ref is not None and np.ptp(ref) > 0
    np.testing.assert_allclose(got, ref, rtol=1e-5, atol=1e-6)
