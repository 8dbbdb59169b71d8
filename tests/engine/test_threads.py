"""BLAS on one thread for interactive queries (engine.threads), checked inside the calls themselves."""
from __future__ import annotations

import threading

import numpy as np
import pytest
from threadpoolctl import ThreadpoolController, threadpool_info

from engine.threads import one_blas_thread


def blas_threads() -> set[int]:
    """Threads of every loaded BLAS library now."""
    return {int(i["num_threads"]) for i in threadpool_info() if i.get("user_api") == "blas"}


@pytest.fixture
def two_blas_threads():
    """BLAS on two threads around the test (so that a missing limit shows, even on a one-core CI box)."""
    import scipy.linalg  # noqa: F401  (load scipy's OpenBLAS too)

    with ThreadpoolController().limit(limits=2, user_api="blas"):
        assert blas_threads() == {2}
        yield


def recording(fn, seen):
    """``fn`` wrapped to append the BLAS threads in force at each call to ``seen``."""
    def wrapper(*args, **kwargs):
        seen.append(blas_threads())
        return fn(*args, **kwargs)

    return wrapper


def test_limit_is_one_inside_and_restored_after(two_blas_threads):
    with one_blas_thread():
        assert blas_threads() == {1}
        with one_blas_thread():
            assert blas_threads() == {1}
        assert blas_threads() == {1}  # the inner exit keeps the outer's limit
    assert blas_threads() == {2}


def test_overlapping_callers_on_two_threads_restore_the_original(two_blas_threads):
    # A enters, B enters, A leaves first, B last: BLAS stays at one thread until B leaves, then
    # returns to two (nested threadpool_limits restored in this order leaves it stuck at one)
    a_in, b_in, a_out = threading.Event(), threading.Event(), threading.Event()
    seen = {}

    def a():
        with one_blas_thread():
            a_in.set()
            b_in.wait(5)
        a_out.set()

    def b():
        a_in.wait(5)
        with one_blas_thread():
            b_in.set()
            a_out.wait(5)
            seen["b after a left"] = blas_threads()

    ts = [threading.Thread(target=a), threading.Thread(target=b)]
    for t in ts:
        t.start()
    for t in ts:
        t.join(10)
    assert seen["b after a left"] == {1}
    assert blas_threads() == {2}


def test_inverse_map_query_on_one_thread(small_manifold, two_blas_threads, monkeypatch):
    from engine.manifold.inverse import InverseMap

    seen = []
    monkeypatch.setattr(InverseMap, "_transform_nd", recording(InverseMap._transform_nd, seen))
    inv = small_manifold.inverse_map
    inv.transform(small_manifold.Fy_[:5, :3] + 0.01)
    assert seen and all(s == {1} for s in seen)
    assert blas_threads() == {2}


def test_local_linear_inverse_on_one_thread(small_manifold, two_blas_threads, monkeypatch):
    from engine.manifold.inverse_local import LocalLinearInverse

    m = small_manifold
    inv = LocalLinearInverse(n_dims=3).fit(m.Fy_, m.Fx_)
    seen = []
    monkeypatch.setattr(np.linalg, "solve", recording(np.linalg.solve, seen))
    inv.transform(m.Fy_[:7])
    assert seen and all(s == {1} for s in seen)


@pytest.mark.parametrize("method, inner", [("viterbi", "_path_x"), ("manifold", "_x"), ("linear", "target_x"),
                                           ("unitselection", "_sample")])
def test_synthesis_on_one_thread(small_manifold, two_blas_threads, monkeypatch, method, inner):
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.methods import make_synthesizer

    m = small_manifold
    syn = make_synthesizer(method, m)
    seen = []
    monkeypatch.setattr(type(syn), inner, recording(getattr(type(syn), inner), seen))
    tg = targets_from_utterance(m, m.corpus_.utterances[2].id)
    syn.synthesize(tg.phones_only() if method == "unitselection" else tg)
    assert seen and all(s == {1} for s in seen)
    assert blas_threads() == {2}


class _RecordingArray(np.ndarray):
    """An array whose products record the BLAS threads in force (``F^x @ components``)."""
    seen: list = []

    def __rmatmul__(self, other):
        _RecordingArray.seen.append(blas_threads())
        return np.asarray(other) @ np.asarray(self)


def test_reconstructing_a_few_frames_on_one_thread_and_many_on_all(small_manifold, two_blas_threads):
    import copy

    from engine.manifold.shape import SMALL_QUERY_ROWS

    sh = copy.copy(small_manifold.shape_)
    sh.components_ = small_manifold.shape_.components_.view(_RecordingArray)
    _RecordingArray.seen = []
    few = sh.inverse_transform(small_manifold.Fx_[:3])
    many = sh.inverse_transform(np.repeat(small_manifold.Fx_[:1], SMALL_QUERY_ROWS + 1, axis=0))
    assert _RecordingArray.seen == [{1}, {2}]  # a click on one thread; reconstructing a corpus on every thread
    np.testing.assert_allclose(np.asarray(few), small_manifold.shape_.inverse_transform(small_manifold.Fx_[:3]))
    assert many.shape[0] == SMALL_QUERY_ROWS + 1


def test_projecting_a_live_frame_on_one_thread(small_manifold, two_blas_threads, monkeypatch):
    from engine.manifold.embedding import Embedding

    seen = []
    monkeypatch.setattr(Embedding, "transform", recording(Embedding.transform, seen))
    Fy = small_manifold.project(small_manifold.corpus_.frames[:4])
    assert Fy.shape == (4, small_manifold.Fy_.shape[1])
    assert seen == [{1}]
