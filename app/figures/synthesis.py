"""Paper fig. 3: an utterance regenerated on the manifold through its own phone mid-points."""
from __future__ import annotations

import numpy as np

from app.figures.style import (
    ARBITRARY,
    GENERATED,
    ORIGINAL,
    below,
    font_pt,
    journal,
    legend_below,
    new_figure,
    one_column,
    place_labels,
    require_fitted,
)

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


@journal
def make_fig3(manifold, *, utterance=None, axes=(0, 1), label_phones: bool = True, width=None,
              height: float | None = None):
    """Fig. 3: a generated trajectory in the first two components of Y.

    The utterance's own phone mid-points are the targets (oracle states,
    :func:`engine.phonetics.targets.targets_from_utterance`); :class:`engine.synthesis.viterbi.ManifoldSynthesizer`
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
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.viterbi import ManifoldSynthesizer

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
    from engine.recordings.kinematics import has_kinematic_labels

    # a corpus without phone labels is regenerated through its kinematic landmarks: say so, never "phones"
    what = "kinematic landmark" if has_kinematic_labels(corpus) else "phone"
    fig = new_figure(width, height or (1.0 if one_column(width) else 0.72) * width)
    ax = fig.subplots()
    lo, = ax.plot(orig[:, a], orig[:, b], "-", color=ORIGINAL, lw=1.4, label="original")
    lg, = ax.plot(gen[:, a], gen[:, b], "-", color=GENERATED, lw=1.4, label="generated (manifold path)")
    lo.set_gid("fig3:original")
    lg.set_gid("fig3:generated")
    mk, = ax.plot(orig[tf, a], orig[tf, b], "o", ms=7, mfc="none", mec=ORIGINAL, mew=1.2, ls="none",
                  label="phone mid-points" if what == "phone" else "kinematic landmarks")
    mk.set_gid("fig3:midpoints")
    ax.set_xlabel(f"$Y_{a + 1}$ {ARBITRARY}")
    ax.set_ylabel(f"$Y_{b + 1}$ {ARBITRARY}")
    legend_below(fig, [lo, lg, mk], gid="fig3:legend")
    text = f" \u201c{u.text}\u201d" if u.text else ""
    ax.set_title(f"Utterance {u.id}{text}\n{len(tf)} {what} targets, RMSE in X {rmse_x:.3g} "
                 f"({corpus.unit_label})")
    notes = []
    if traj.warnings:
        notes.append(f"{len(traj.warnings)} gap(s) not reachable in time; ended at the nearest reachable state")
    note = below(ax, "; ".join(notes)) if notes else None
    left_out = 0
    if label_phones:  # placed last, against the final layout, so that no two labels collide
        args = (ax, orig[tf][:, [a, b]], traj.target_labels)
        trial: list = []
        left_out = place_labels(*args, fontsize=font_pt(-1.5), placed_texts=trial)
        if left_out:  # say so under the axes (which changes the layout): place them again against it
            for t in trial:
                t.remove()
            notes.append(f"{left_out} {what} label(s) left out where they would overlap")
            if note is not None:
                note.remove()
            note = below(ax, "; ".join(notes))
            left_out = place_labels(*args, fontsize=font_pt(-1.5))
            notes = notes[:-1] + ([f"{left_out} {what} label(s) left out where they would overlap"] if left_out
                                  else [])
            note.set_text("; ".join(notes))
    fig.lipspace.update(utterance=u.id, target_frames=tf, labels=list(traj.target_labels), rmse_x=rmse_x,
                        rmse_y=rmse_y, warnings=list(traj.warnings), labels_left_out=left_out)
    return fig
