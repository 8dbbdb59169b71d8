"""The Dask path of a build matches the in-process one (issue 13), on a two-worker LocalCluster."""
import numpy as np
import pytest
from scipy.linalg import subspace_angles

pytest.importorskip("distributed")

#: largest principal angle (degrees) allowed between the Dask and in-process F^x / F^y subspaces
#: (measured: 3e-5 deg for F^x, 8e-5 deg for the first 3 columns of F^y, 1,956 frames)
ANGLE_TOL_DEG = 0.01
#: adjusted Rand index of the Dask build's state labels against the in-process build's
STATE_ARI_MIN = 0.99  # measured 1.0 (1,956 frames, K = 40)
#: fraction of frames in the same movement class in both builds
CLASS_AGREEMENT_MIN = 0.995  # measured 1.0


@pytest.fixture(scope="module")
def executor(tmp_path_factory, dask_cluster):
    from distributed import Client

    from engine.scale.executor import DaskExecutor

    ex = DaskExecutor(Client(dask_cluster), chunk_dir=tmp_path_factory.mktemp("blocks"), block_frames=512)
    yield ex
    ex.close()  # the client only: the session's cluster stays


@pytest.fixture(scope="module")
def corpus(small_corpus):
    """The first ~2,000 frames (whole utterances) of the small synthetic talker."""
    ids = [u.id for u in small_corpus.utterances if u.stop <= 2000]
    return small_corpus.subset(ids)


@pytest.fixture(scope="module")
def in_process(corpus):
    from engine.manifold.model import Manifold

    return Manifold(n_states=40).fit(corpus)


@pytest.fixture(scope="module")
def dask_manifold(corpus, executor):
    from engine.manifold.model import Manifold

    return Manifold(n_states=40).fit(corpus, executor=executor)


def _max_angle(a, b):
    return float(np.degrees(subspace_angles(a.astype(np.float64), b.astype(np.float64)).max()))


def test_frame_blocks_round_trip(tmp_path):
    from engine.recordings.frame_blocks import store_frame_blocks
    from engine.scale.executor import open_frame_blocks

    F = np.random.default_rng(0).standard_normal((2400, 7)).astype(np.float32)
    paths = store_frame_blocks(F, tmp_path, block_frames=1000)
    assert [p.name for p in paths] == ["block_00000.npy", "block_00001.npy"]  # 400-frame tail joins block 1
    arr = open_frame_blocks(paths)
    assert arr.chunks[0] == (1000, 1400)
    np.testing.assert_array_equal(arr.compute(), F)


def test_dask_build_matches_in_process(dask_manifold, in_process):
    d, m = dask_manifold, in_process
    assert d.shape_.n_components_ == m.shape_.n_components_
    assert _max_angle(d.Fx_, m.Fx_) < ANGLE_TOL_DEG
    assert _max_angle(d.Fy_[:, :3], m.Fy_[:, :3]) < ANGLE_TOL_DEG
    np.testing.assert_allclose(d.embedding_.explained_variance_[:3], m.embedding_.explained_variance_[:3],
                               rtol=1e-3)
    assert "_operator_factory" not in vars(d.embedding_)  # the Dask operator is not kept
    # the same range finder: the same power iterations (early stop included) and range width
    assert (d.shape_.n_iter_, d.shape_.n_range_) == (m.shape_.n_iter_, m.shape_.n_range_)


def test_dask_projection_and_assignment_match(executor, in_process):
    m = in_process
    G = m.G_[:1500]
    np.testing.assert_allclose(executor.project(m.embedding_, G, block=700), m.embedding_.transform(G),
                               rtol=1e-4, atol=1e-3 * float(np.abs(m.Fy_).max()))
    np.testing.assert_array_equal(executor.assign(m.states_.centroids_, m.Fy_, block=1000), m.states_.labels_)


def test_small_blocks_are_refused(executor):
    from engine.scale.executor import DaskExecutor

    with pytest.raises(ValueError, match="block_frames must be >= 256"):
        DaskExecutor(executor.client, block_frames=10)


def test_dask_tangent_frames_and_states_equal_in_process_on_the_same_fy(executor, in_process):
    """Given the same F^y, the per-block Dask tasks reproduce the in-process tangent frames and state graph."""
    from engine.graph.states import StateGraph
    from engine.manifold.tangent import TangentFrames
    from engine.recordings.kinematics import lip_aperture

    m = in_process
    b = m.corpus_.bounds
    args = (m.Fy_, b, lip_aperture(m.corpus_))
    ref = TangentFrames().fit(*args, rate=m.corpus_.rate)
    got = TangentFrames().fit(*args, rate=m.corpus_.rate, executor=executor)
    for attr in ("s_", "v_", "velocity_", "classes_", "neighbor_scores_"):
        np.testing.assert_array_equal(getattr(got, attr), getattr(ref, attr))
    assert got.n_degenerate_ == ref.n_degenerate_

    class SmallBlocks:  # blocks of 300 frames: transitions across block edges must be counted once
        def map_row_blocks(self, fn, n, *shared, block=None):
            return executor.map_row_blocks(fn, n, *shared, block=300)

    ref_s = StateGraph(n_states=40).fit(m.Fy_, b)
    got_s = StateGraph(n_states=40).fit(m.Fy_, b, executor=SmallBlocks())
    np.testing.assert_array_equal(got_s.labels_, ref_s.labels_)
    for attr in ("counts_", "adjacency_", "transition_"):
        assert (getattr(got_s, attr) != getattr(ref_s, attr)).nnz == 0, attr
    assert got_s.counts_.sum() == m.corpus_.n_frames - len(b)  # one transition per frame with a successor


def test_dask_build_states_and_classes_agree(dask_manifold, in_process):
    """Whole builds: F^y differs by round-off, so K-means may move a few frames between neighbouring states."""
    from sklearn.metrics import adjusted_rand_score

    d, m = dask_manifold, in_process
    assert adjusted_rand_score(m.states_.labels_, d.states_.labels_) > STATE_ARI_MIN
    assert np.mean(d.tangent_.classes_ == m.tangent_.classes_) > CLASS_AGREEMENT_MIN


def test_shape_tasks_never_return_a_block_of_frames(executor, dask_cluster, tmp_path):
    """Every task of the Dask shape space reads its block of F and multiplies it: none returns a block of
    F, which a worker would hold until every task using it had run (blocks piling up). Largest result
    seen by the scheduler: a thin block (512 x 30 float32) or a C x r sum, not 512 x 300."""
    from distributed.diagnostics.plugin import SchedulerPlugin

    from engine.manifold.shape import ShapeSpace
    from engine.recordings.frame_blocks import BlockFrames, store_frame_blocks

    class LargestResult(SchedulerPlugin):
        largest = (0, None)

        def transition(self, key, start, finish, *args, **kwargs):
            if finish == "memory" and kwargs.get("nbytes", 0) > self.largest[0]:
                self.largest = (kwargs["nbytes"], key)

    rng = np.random.default_rng(1)
    F = (rng.standard_normal((2048, 8)) @ rng.standard_normal((8, 300)) * 3 + 0.01 *
         rng.standard_normal((2048, 300)) + 5).astype(np.float32)
    frames = BlockFrames.from_files(store_frame_blocks(F, tmp_path, block_frames=512))
    plugin = LargestResult()
    dask_cluster.scheduler.add_plugin(plugin, name="largest-result")
    try:
        Fx = executor.fit_shape(ShapeSpace(max_components=20), frames)
    finally:
        dask_cluster.scheduler.remove_plugin(name="largest-result")
    block_bytes = 512 * F.shape[1] * 4
    assert 0 < plugin.largest[0] < block_bytes / 2, plugin.largest
    ref = ShapeSpace(max_components=20).fit(F)
    assert Fx.shape[1] == ref.n_components_
    assert _max_angle(Fx, ref.transform(F)) < ANGLE_TOL_DEG
