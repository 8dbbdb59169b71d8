"""The k-NN density of a drawn point cloud, kept in the cache folder for the next time it is shown (Qt-free).

The manifold view colours its points by their k-nearest-neighbour density by default
(:func:`app.models.state.knn_density`). Computing it needs SciPy's k-d tree, whose import alone
(``scipy.spatial``: Qhull, LAPACK's Cython bindings) costs a few tenths of a second of every start of
the window, more than the query. Opening the same manifold again — the synthetic talker, a lab's
own corpus — finds the densities here instead: ``<cache>/density/<key>.npy``, one float32 per
point, the key a hash of the drawn coordinates, ``k``, the number of dimensions and the source of
the function that computes them, so a changed cloud or formula never reads an old entry. Entries are
small (4 bytes per point, at most :data:`app.models.lod.DEFAULT_MAX_POINTS` points are drawn one by
one) and the folder keeps the :data:`MAX_ENTRIES` most recently used. A folder that cannot be
written, or an entry that cannot be read or does not fit, only costs computing the densities again.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
from pathlib import Path

import numpy as np

__all__ = ["MAX_ENTRIES", "density_dir", "density_key", "cached_knn_density"]

#: how many clouds' densities the cache keeps (the most recently used)
MAX_ENTRIES = 32


def density_dir(folder=None) -> Path:
    """Where the densities are kept: ``<cache>/density``."""
    from app.files.cache import cache_dir

    return (Path(folder) if folder is not None else cache_dir()) / "density"


def density_key(Y, k: int, n_dims: int) -> str:
    """16 hex digits naming the densities of the first ``n_dims`` columns of ``Y`` with ``k`` neighbours."""
    import inspect

    from app.models.state.derived import knn_density

    Y = np.ascontiguousarray(np.asarray(Y, dtype=np.float64)[:, :n_dims])
    h = hashlib.blake2b(digest_size=8)
    h.update(f"{Y.shape}|{int(k)}|{int(n_dims)}|".encode())
    h.update(inspect.getsource(knn_density).encode())
    h.update(memoryview(Y).cast("B"))
    return h.hexdigest()


def _read(path: Path, n: int, root: Path):
    """The densities stored at ``path`` if they are ``n`` finite float32 values, else None."""
    try:
        with open(path, "rb") as fh:
            d = np.load(fh, allow_pickle=False)
    except (OSError, ValueError, EOFError):
        return None
    if d.dtype != np.float32 or d.shape != (n,) or not np.isfinite(d).all():
        return None
    from engine.files.ownership import mark, owned

    if owned(path, root):  # recently used: kept by the pruning (the marker records the new time)
        with contextlib.suppress(OSError):
            os.utime(path)
            mark(path, root)
    return d


def _write(path: Path, d: np.ndarray, root: Path) -> None:
    from engine.files.atomic import atomic_write
    from engine.files.ownership import mark

    with atomic_write(path) as tmp:
        np.save(tmp, d, allow_pickle=False)
    mark(path, root)  # Lipspace's own: pruning and 'lipspace cache --clear' may delete it
    _prune(root)


def _prune(root: Path) -> None:
    """Delete the least recently used entries beyond :data:`MAX_ENTRIES` (Lipspace's own only)."""
    from app.files.cache import entries
    from engine.files.ownership import unmark

    mine = [e.path for e in entries(root) if e.kind == "density" and e.owned]  # oldest first
    for p in mine[:max(0, len(mine) - MAX_ENTRIES)]:
        with contextlib.suppress(OSError):
            p.unlink()
            unmark(p, root)


def cached_knn_density(Y, k: int = 10, n_dims: int = 3, *, folder=None) -> np.ndarray:
    """:func:`app.models.state.knn_density` of ``Y``, read from the cache when this cloud's was stored
    there, else computed and stored.

    Parameters
    ----------
    Y : ndarray of shape (N, >=n_dims)
    k : int, default=10
    n_dims : int, default=3
    folder : path, optional
        The cache folder (default :func:`app.files.cache.cache_dir`).

    Returns
    -------
    ndarray of shape (N,) float32
    """
    from app.files.cache import cache_dir
    from app.models.state.derived import knn_density

    Y = np.asarray(Y)
    root = Path(folder) if folder is not None else cache_dir()
    path = density_dir(root) / f"{density_key(Y, k, n_dims)}.npy"
    d = _read(path, Y.shape[0], root) if path.is_file() else None
    if d is not None:
        return d
    d = knn_density(Y, k, n_dims)
    with contextlib.suppress(OSError):
        _write(path, d, root)
    return d
