"""Paper fig. 3: an utterance regenerated on the manifold through its own phone mid-points."""
from __future__ import annotations

import numpy as np

from app.figures._style import GENERATED, ORIGINAL, below, new_figure, place_labels, require_fitted

__all__ = ["make_fig3", "default_utterance"]


def default_utterance(corpus, *, min_phones: int = 8) -> str:
    """Id of the utterance fig. 3 shows by default.

    The utterance of median length among those with at least ``min_phones`` phones
    (all utterances if none has that many): representative, and deterministic.
    """
    utts = [u for u in corpus.utterances if len(u.phones) >= min_phones] or list(corpus.utterances)
    utts = [u for u in utts if len(u.phones) >= 2] or utts
    order = sorted(range(len(utts)), key=lambda k: (utts[k].n_frames, k))
    return utts[order[len(order) // 2]].id


def make_fig3(manifold, *, utterance=None, axes=(0, 1), label_phones: bool = True, width: float = 6.0,
              height: float = 5.0):
    """Fig. 3: a generated trajectory in the first two components of Y.

    The utterance's own phone mid-points are the targets (oracle states,
    :func:`engine.targets.targets_from_utterance`); :class:`engine.synthesis.ManifoldSynthesizer`
    fills every gap with the most probable state path of exactly the gap's length
    (``strict=False``: a gap that cannot be bridged in time ends at the nearest
    reachable state and the figure notes it). Original black, generated red,
    circles at the phone mid-points (on the original).

    Parameters
    ----------
    utterance : str or None
        Corpus utterance id (default :func:`default_utterance`).
    axes : (int, int), default=(0, 1)
        Y dimensions shown (the paper: the first two).
    label_phones : bool, default=True
        Write each mid-point's phone label beside its circle.
    """
    require_fitted(manifold, "states_")
    from engine.synthesis import ManifoldSynthesizer
    from engine.targets import targets_from_utterance

    corpus = manifold.corpus_
    a, b = (int(v) for v in axes)
    k = manifold.Fy_.shape[1]
    if not (0 <= a < 3 and 0 <= b < 3 and a != b and max(a, b) < k):
        raise ValueError(f"axes {tuple(axes)} must be two different Y dims among the first {min(3, k)} "
                         "(the generated path lives in the state centroids' dims)")
    uid = default_utterance(corpus) if utterance is None else str(utterance)
    try:
        u = corpus.utterance(uid)
    except KeyError as exc:
        raise ValueError(exc.args[0]) from None
    targets = targets_from_utterance(manifold, uid, on_collision="merge")
    from engine.threads import one_blas_thread

    with one_blas_thread():  # the inverse map's Delaunay set-up: one tiny LAPACK call per simplex
        traj = ManifoldSynthesizer(strict=False).fit(manifold).synthesize(targets)
    orig = np.asarray(manifold.Fy_[u.start:u.stop], dtype=np.float64)
    gen = np.asarray(traj.Fy, dtype=np.float64)
    if gen.shape[1] <= max(a, b):
        raise ValueError(f"the generated path has only {gen.shape[1]} Y dims; choose axes below that")
    fx_o = np.asarray(manifold.Fx_[u.start:u.stop], dtype=np.float64)
    fx_g = np.asarray(traj.Fx, dtype=np.float64)
    rmse_x = float(np.sqrt(np.mean(np.sum((fx_g - fx_o) ** 2, axis=1))))
    rmse_y = float(np.sqrt(np.mean(np.sum((gen[:, [a, b]] - orig[:, [a, b]]) ** 2, axis=1))))
    tf = np.asarray(traj.target_frames, dtype=np.int64)
    from engine.kinematics import has_kinematic_labels

    # a corpus without phone labels is regenerated through its kinematic landmarks: say so, never "phones"
    what = "kinematic landmark" if has_kinematic_labels(corpus) else "phone"
    fig = new_figure(width, height)
    ax = fig.subplots()
    lo, = ax.plot(orig[:, a], orig[:, b], "-", color=ORIGINAL, lw=1.4, label="original")
    lg, = ax.plot(gen[:, a], gen[:, b], "-", color=GENERATED, lw=1.4, label="generated (manifold path)")
    lo.set_gid("fig3:original")
    lg.set_gid("fig3:generated")
    mk, = ax.plot(orig[tf, a], orig[tf, b], "o", ms=7, mfc="none", mec=ORIGINAL, mew=1.2, ls="none",
                  label="phone mid-points" if what == "phone" else "kinematic landmarks")
    mk.set_gid("fig3:midpoints")
    ax.set_xlabel(f"$Y_{a + 1}$")
    ax.set_ylabel(f"$Y_{b + 1}$")
    ax.legend(frameon=False, fontsize=8, loc="best")
    text = f" \u201c{u.text}\u201d" if u.text else ""
    ax.set_title(f"Utterance {u.id}{text}\n{len(tf)} {what} targets, RMSE in X {rmse_x:.3g}", fontsize=9)
    notes = []
    if traj.warnings:
        notes.append(f"{len(traj.warnings)} gap(s) not reachable in time; ended at the nearest reachable state")
    if notes:
        below(ax, "; ".join(notes))
    left_out = 0
    if label_phones:  # placed last, against the final layout, so that no two labels collide
        left_out = place_labels(ax, orig[tf][:, [a, b]], traj.target_labels, fontsize=7)
        if left_out:
            fig.text(0.01, 0.005, f"{left_out} {what} label(s) left out where they would overlap", fontsize=6.5,
                     color="0.35", ha="left", va="bottom").set_in_layout(False)
    fig.lipspace.update(utterance=u.id, target_frames=tf, labels=list(traj.target_labels), rmse_x=rmse_x,
                        rmse_y=rmse_y, warnings=list(traj.warnings), labels_left_out=left_out)
    return fig
