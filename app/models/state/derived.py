"""What the views derive from a manifold: k-NN density, every frame's phone, clusters (Qt-free).

The pure functions compute them; :func:`prepare_derived` computes them ahead of time (in the
loading worker) and :class:`DerivedCaches`, a part of :class:`app.models.state.AppState`, picks
them up or computes each once per manifold on first use.
"""
from __future__ import annotations

import weakref

import numpy as np

__all__ = ["corpus_palette", "knn_density", "frame_phones", "frame_phone_codes", "cluster_table", "prepare_derived",
           "PREPARED", "DerivedCaches"]

#: derived data computed ahead of time per manifold object (see prepare_derived)
PREPARED: weakref.WeakKeyDictionary = weakref.WeakKeyDictionary()


def prepare_derived(manifold, progress=None, *, density=None) -> None:
    """Compute what the views derive from ``manifold`` ahead of showing it (Qt-free, any thread).

    The level of detail of the drawn cloud (:func:`app.models.lod.cloud_detail`: every frame up to
    ``app.models.lod.DEFAULT_MAX_POINTS``, groups of frames above), the k-NN density of every frame
    (only while every frame is drawn: a grouped cloud carries its own density; ``density(Y)``
    computes it, :func:`knn_density` by default: the loader passes one that keeps it in the cache
    folder for the next time the cloud is shown, :func:`app.files.density_cache.cached_knn_density`),
    the phone of every frame and the phone clusters are computed here, e.g. in the loading worker, and
    picked up by :meth:`AppState.set_manifold`, so that showing a manifold does not freeze the window.
    The state graph's forms for hemisphere and path queries are not (they need SciPy's sparse package,
    0.2 s of import the manifold's first frame need not wait for): the manifold view builds them in a
    worker once that frame is drawn. Reports stage ``"preparing the views"``.
    A corpus whose phone clusters cannot be fitted is left for the clusters panel to
    report, as without this step.
    """
    from app.models.lod import cloud_detail
    from engine.progress import report

    stage = "preparing the views"
    report(progress, stage, 0, 4)
    out = {"cloud": cloud_detail(manifold.Fy_, manifold.states_.labels_)}
    report(progress, stage, 1, 4)
    if out["cloud"].whole:
        out["density"] = (density or knn_density)(manifold.Fy_)
    report(progress, stage, 2, 4)
    out["phone_codes"] = frame_phone_codes(manifold.corpus_)
    report(progress, stage, 3, 4)
    try:
        from engine.manifold.clusters import clusters_of

        # phone mid-points, or the kinematic landmarks of a corpus without phone labels
        out["clusters"], out["cluster_kind"], out["cluster_note"] = clusters_of(manifold)
    except ValueError:
        pass  # the panel computes (and reports) it when shown
    out["palette"] = corpus_palette(manifold.corpus_)
    from app.models.palette import qualitative_colours

    qualitative_colours(1)  # the palette's colour sequence, made once per process: here, not in the window's thread
    report(progress, stage, 4, 4)
    PREPARED[manifold] = out


def corpus_palette(corpus):
    """The session palette of ``corpus``: its phones, speakers, utterances and the levels of every
    per-utterance field (ranked as ``lipspace compare`` ranks them for its figure)."""
    from app.models.palette import SessionPalette
    from engine.comparison.fields import utterance_fields

    fields = {k: v for k, v in utterance_fields(corpus).items() if k != "speaker"}
    return SessionPalette.for_corpus(corpus, fields=fields)


def knn_density(Y, k: int = 10, n_dims: int = 3) -> np.ndarray:
    """Log k-nearest-neighbour density of each point in the first ``n_dims`` dims of ``Y``.

    ``log(k / (N * V_d * r_k^d))`` with r_k the distance to the k-th neighbour.

    Parameters
    ----------
    Y : ndarray of shape (N, >=n_dims)
    k : int, default=10

    Returns
    -------
    ndarray of shape (N,) float32
    """
    from scipy.spatial import cKDTree
    from scipy.special import gammaln

    Y = np.asarray(Y, dtype=np.float64)[:, :n_dims]
    N, d = Y.shape
    if N < 2:
        return np.zeros(N, dtype=np.float32)
    k = int(min(max(k, 1), N - 1))
    r, _ = cKDTree(Y).query(Y, k=k + 1)
    rk = np.maximum(r[:, -1], np.finfo(np.float64).tiny ** (1.0 / d))
    log_vd = (d / 2) * np.log(np.pi) - gammaln(d / 2 + 1)
    return (np.log(k / N) - log_vd - d * np.log(rk)).astype(np.float32)


def frame_phones(corpus) -> np.ndarray:
    """Phone label of every corpus frame; '' where no phone covers it.

    Returns ndarray of shape (N,) of str.
    """
    codes, names = frame_phone_codes(corpus)
    return np.array(list(names) + [""])[codes]


def frame_phone_codes(corpus) -> tuple[np.ndarray, list[str]]:
    """Every corpus frame's phone as a code: ``(codes (N,) int32, names)``.

    A phone covers its frames from the one nearest its start up to (not including) the
    one nearest its end, and at least its first frame; where two cover a frame the later
    phone wins. ``names`` are the labels that cover a frame, sorted; ``codes[i]`` indexes
    them, ``len(names)`` where no phone covers frame i. Vectorised over the phones (no
    loop over frames or phones in Python).
    """
    from engine.recordings.corpus import label_codes

    N = corpus.n_frames
    _mid, labs, _utt, a, b = corpus.phone_table()
    labels, inv = label_codes(labs)  # np.unique's result, without sorting a million strings
    e = np.maximum(b, a + 1)
    codes = np.full(N, len(labels), np.int64)
    if len(a) and np.all(a[1:] >= a[:-1]):  # phones in corpus order (as Corpus.validate keeps them)
        f = np.arange(N)
        j = np.searchsorted(a, f, side="right") - 1  # the last phone starting at or before each frame
        reach = np.maximum.accumulate(e)  # the furthest end of any phone so far
        pending = np.flatnonzero(j >= 0)
        while pending.size:  # the latest phone covering each frame: walk back while one could
            jj = j[pending]
            hit = e[jj] > pending
            codes[pending[hit]] = inv[jj[hit]]
            more = ~hit & (jj > 0)
            more[more] = reach[jj[more] - 1] > pending[more]
            pending = pending[more]
            j[pending] -= 1
    else:
        for k in range(len(a)):
            codes[a[k]:e[k]] = inv[k]
    used = np.bincount(codes, minlength=len(labels) + 1)[:len(labels)] > 0
    remap = np.full(len(labels) + 1, int(used.sum()), np.int64)
    remap[np.flatnonzero(used)] = np.arange(int(used.sum()))
    return remap[codes].astype(np.int32), [str(x) for x in labels[used]]


def cluster_table(clusters) -> list[dict]:
    """Rows of the phone table from fitted PhoneClusters, most frequent phone first.

    Keys as :meth:`engine.manifold.clusters.PhoneClusters.table`: phone, count, opening_fraction,
    lipreading_class, nearest_y, separation_y, separation_x (Bhattacharyya distances), ...
    """
    return sorted(clusters.table(), key=lambda r: (-r["count"], r["phone"]))




class DerivedCaches:
    """The per-manifold derived data of :class:`app.models.state.AppState`, each computed once."""

    def _take_prepared(self, manifold) -> None:
        """Pick up what :func:`prepare_derived` computed for ``manifold`` (the rest is computed on demand)."""
        pre = PREPARED.get(manifold, {}) if manifold is not None else {}
        self._density, self._phone_codes, self._clusters, self._cloud = (
            pre.get(k) for k in ("density", "phone_codes", "clusters", "cloud"))
        self._cluster_kind, self._cluster_note = pre.get("cluster_kind"), pre.get("cluster_note")
        self._phones = None
        self._derived: dict = {}  # per-manifold values of the views, computed once (see derived)
        self._utt_starts = None

    def _palette_for(self, manifold):
        """The session palette of ``manifold``'s corpus (prepared in the loading worker, else made now)."""
        if manifold is None:
            return None
        pre = PREPARED.get(manifold, {})
        if "palette" in pre:  # a copy: each state's colours are its own (another state of this manifold keeps its)
            import copy

            return copy.deepcopy(pre["palette"])
        return corpus_palette(manifold.corpus_)

    def _require(self):
        if self.manifold is None:
            raise RuntimeError("no manifold is loaded; open a corpus or manifold first")
        return self.manifold

    @property
    def n_frames(self) -> int:
        return int(self._require().Fy_.shape[0])

    @property
    def n_states(self) -> int:
        return int(self._require().states_.centroids_.shape[0])

    @property
    def density(self) -> np.ndarray:
        """k-NN log density of every frame in F^y, computed once per manifold."""
        if self._density is None:
            self._density = knn_density(self._require().Fy_)
        return self._density

    @property
    def cloud(self):
        """The level of detail the manifold view draws (:class:`app.models.lod.CloudDetail`), once per manifold."""
        if self._cloud is None:
            from app.models.lod import cloud_detail

            m = self._require()
            self._cloud = cloud_detail(m.Fy_, m.states_.labels_)
        return self._cloud

    @property
    def phone_codes(self) -> np.ndarray:
        """(N,) int32: every frame's phone as an index into :attr:`phone_names` (``len(phone_names)``:
        no phone), computed once per manifold."""
        if self._phone_codes is None:
            self._phone_codes = frame_phone_codes(self._require().corpus_)
        return self._phone_codes[0]

    @property
    def phone_names(self) -> list[str]:
        """The phone labels covering at least one frame, sorted."""
        _ = self.phone_codes  # computes and caches both
        return self._phone_codes[1]

    @property
    def phones(self) -> np.ndarray:
        """Phone label of every frame ('' outside phones), computed once per manifold."""
        if self._phones is None:
            self._phones = np.array(list(self.phone_names) + [""])[self.phone_codes]
        return self._phones

    def phone_of(self, i: int) -> str:
        """Frame ``i``'s phone ('' outside phones)."""
        c = int(self.phone_codes[int(i)])
        names = self.phone_names
        return names[c] if c < len(names) else ""

    def utterance_of(self, i: int):
        """The utterance (:class:`engine.recordings.corpus.Utterance`) frame ``i`` belongs to."""
        c = self._require().corpus_
        if self._utt_starts is None:
            self._utt_starts = np.array([u.start for u in c.utterances], dtype=np.int64)
        return c.utterances[int(np.searchsorted(self._utt_starts, int(i), side="right")) - 1]

    def derived(self, key, compute):
        """``compute()`` once per manifold under ``key`` (the views' per-manifold tables, e.g. a colouring's)."""
        if key not in self._derived:
            self._derived[key] = compute()
        return self._derived[key]

    @property
    def clusters(self):
        """The manifold's :class:`engine.manifold.clusters.PhoneClusters`, fitted once per manifold: of its phone
        mid-points, or of its kinematic landmarks when the corpus has no phone labels
        (:func:`engine.manifold.clusters.clusters_of`; :attr:`cluster_kind` says which)."""
        if self._clusters is None:
            from engine.manifold.clusters import clusters_of

            self._clusters, self._cluster_kind, self._cluster_note = clusters_of(self._require())
        return self._clusters

    @property
    def cluster_kind(self) -> str:
        """What the clusters are of: ``"phones"`` or ``"kinematic"`` (landmarks)."""
        _ = self.clusters  # computed with the clusters
        return self._cluster_kind

    @property
    def cluster_note(self) -> str | None:
        """For landmark clusters, the sentence saying what the labels are (None for phones)."""
        _ = self.clusters  # computed with the clusters
        return self._cluster_note

    def cluster_rows(self) -> list[dict]:
        """The phone table of the clusters panel (see :func:`cluster_table`)."""
        return cluster_table(self.clusters)
