"""The densities of a drawn cloud are kept in the cache folder (app.files.density_cache): the same cloud
reads them back, a changed cloud or a damaged entry computes them anew, the folder keeps the most
recently used, and 'lipspace cache' lists and clears them."""
from __future__ import annotations

import subprocess
import sys
import textwrap

import numpy as np
import pytest

from app.files import density_cache
from app.files.cache import clear, entries
from app.models.state.derived import knn_density


@pytest.fixture
def cloud():
    rng = np.random.default_rng(7)
    return rng.normal(size=(500, 5)).astype(np.float32)


class _Refused:
    def __init__(self, *_a, **_k):
        raise AssertionError("computed again, not read from the cache")


def test_a_cloud_shown_again_reads_its_densities(tmp_path, cloud, monkeypatch):
    first = density_cache.cached_knn_density(cloud, folder=tmp_path)
    np.testing.assert_array_equal(first, knn_density(cloud))
    (e,) = entries(tmp_path)
    assert e.kind == "density" and e.owned and e.size > 4 * len(cloud)
    monkeypatch.setattr("scipy.spatial.cKDTree", _Refused)
    again = density_cache.cached_knn_density(cloud.copy(), folder=tmp_path)
    np.testing.assert_array_equal(again, first)
    assert again.dtype == np.float32


def test_a_changed_cloud_or_neighbourhood_computes_anew(tmp_path, cloud):
    base = density_cache.cached_knn_density(cloud, folder=tmp_path)
    moved = cloud.copy()
    moved[3, 1] += 0.5  # one point moved in the drawn dimensions
    np.testing.assert_array_equal(density_cache.cached_knn_density(moved, folder=tmp_path), knn_density(moved))
    beyond = cloud.copy()
    beyond[:, 4] += 1.0  # not drawn: the same densities, the same entry
    np.testing.assert_array_equal(density_cache.cached_knn_density(beyond, folder=tmp_path), base)
    np.testing.assert_array_equal(density_cache.cached_knn_density(cloud, k=5, folder=tmp_path), knn_density(cloud, 5))
    assert len(entries(tmp_path)) == 3


@pytest.mark.parametrize("damage", [b"not an npy file", "short", "nan"])
def test_a_damaged_entry_is_computed_anew_and_replaced(tmp_path, cloud, damage):
    want = density_cache.cached_knn_density(cloud, folder=tmp_path)
    (e,) = entries(tmp_path)
    if damage == "short":
        np.save(e.path, want[:-1])
    elif damage == "nan":
        bad = want.copy()
        bad[0] = np.nan
        np.save(e.path, bad)
    else:
        e.path.write_bytes(damage)
    np.testing.assert_array_equal(density_cache.cached_knn_density(cloud, folder=tmp_path), want)
    np.testing.assert_array_equal(np.load(e.path), want)  # written again


def test_a_cache_that_cannot_be_written_costs_only_the_computing(tmp_path, cloud):
    (tmp_path / "density").write_text("a file where the folder would be")
    np.testing.assert_array_equal(density_cache.cached_knn_density(cloud, folder=tmp_path), knn_density(cloud))


def test_the_folder_keeps_the_most_recently_used(tmp_path, cloud, monkeypatch):
    import os
    import time

    from engine.files.ownership import mark

    monkeypatch.setattr(density_cache, "MAX_ENTRIES", 2)
    clouds = [cloud + i for i in range(3)]
    paths = []
    for i, c in enumerate(clouds[:2]):
        density_cache.cached_knn_density(c, folder=tmp_path)
        paths.append(density_cache.density_dir(tmp_path) / f"{density_cache.density_key(c, 10, 3)}.npy")
        os.utime(paths[-1], (time.time() - 100 + i, time.time() - 100 + i))
        mark(paths[-1], tmp_path)  # as written then
    density_cache.cached_knn_density(clouds[0], folder=tmp_path)  # read: the first is now the most recent
    density_cache.cached_knn_density(clouds[2], folder=tmp_path)
    left = {e.path for e in entries(tmp_path)}
    assert all(e.owned for e in entries(tmp_path))  # still Lipspace's own after being read
    assert len(left) == 2 and paths[0] in left and paths[1] not in left


def test_clear_removes_the_densities_and_their_folder(tmp_path, cloud):
    density_cache.cached_knn_density(cloud, folder=tmp_path)
    assert [e.kind for e in clear(tmp_path)] == ["density"]
    assert not (tmp_path / "density").exists()


def test_a_manifold_opened_again_is_prepared_without_scipy(tmp_path, app_manifold):
    """The second start on the same manifold reads the densities: SciPy's spatial package (its import alone a few
    tenths of a second of the window's start) is not imported, nor any of SciPy (the state graph's csr matrices
    wait for their first use); the densities are the first start's."""
    path = tmp_path / "m.npz"
    app_manifold.save(path)
    code = textwrap.dedent("""
        import sys
        import numpy as np
        from app.files.source_loading import load_source
        from app.models.state.derived import PREPARED
        m, _src = load_source(sys.argv[1])
        np.save(sys.argv[2], PREPARED[m]["density"])
        print("SPATIAL", "scipy.spatial" in sys.modules, "SCIPY", "scipy" in sys.modules)
    """)
    env = {**__import__("os").environ, "LIPSPACE_CACHE_DIR": str(tmp_path / "cache")}
    seen = []
    for run in range(2):
        r = subprocess.run([sys.executable, "-c", code, str(path), str(tmp_path / f"d{run}.npy")],
                           capture_output=True, text=True, env=env, timeout=120)
        assert r.returncode == 0, r.stderr
        seen.append(r.stdout.strip().splitlines()[-1])
    assert seen == ["SPATIAL True SCIPY True", "SPATIAL False SCIPY False"]
    np.testing.assert_array_equal(np.load(tmp_path / "d0.npy"), np.load(tmp_path / "d1.npy"))
