"""Paper fig. 3: an utterance regenerated on the manifold through its own phone mid-points."""
from __future__ import annotations

import numpy as np

from app.figures.colours import GENERATED, ORIGINAL, palette_for
from app.figures.labels import place_labels
from app.figures.style import (
    ARBITRARY,
    below,
    fit_lines,
    font_pt,
    journal,
    legend_below,
    new_figure,
    one_column,
    require_fitted,
)

__all__ = ["make_fig3", "default_utterance"]

#: what the figure says about the utterance: the manifold was built with it (lipspace evaluate holds utterances out)
IN_TRAINING = "in the manifold's own data (not held out)"


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
              height: float | None = None, palette=None):
    """Fig. 3: a generated trajectory in the first two components of Y.

    The utterance's own phone mid-points are the targets (oracle states,
    :func:`engine.phonetics.targets.targets_from_utterance`); :class:`engine.synthesis.viterbi.ViterbiSynthesizer`
    fills every gap with the most probable state path of exactly the gap's length
    (``strict=False``: a gap that cannot be bridged in time ends at the nearest
    reachable state and the figure notes it). Original black, generated red (the
    window's colours), circles at the targets (on the original). Phone targets are
    labelled beside their circles where nothing else is (never over a line; a label with
    no free place is left out and counted in the note); kinematic landmarks (a corpus
    without phone labels) are few kinds repeated, so their circles take the session
    palette's landmark colours, named in the legend. The title gives the error in X (the
    lip shape, in the corpus's unit) and in the plane shown (arbitrary units); a note says
    that the utterance is part of the manifold's own data (not held out).

    Parameters
    ----------
    utterance : str or None
        Corpus utterance id (default :func:`default_utterance`).
    axes : (int, int), default=(0, 1)
        Y dimensions shown (the paper: the first two).
    label_phones : bool, default=True
        Write each phone target's label beside its circle.
    palette : app.models.palette.SessionPalette, optional
        The session's palette (default: the corpus's own): the landmarks' colours.
    """
    require_fitted(manifold, "states_")
    from engine.phonetics.targets import targets_from_utterance
    from engine.synthesis.viterbi import ViterbiSynthesizer

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
        traj = ViterbiSynthesizer(strict=False).fit(manifold).synthesize(targets)
    orig = np.asarray(manifold.Fy_[u.start:u.stop], dtype=np.float64)
    gen = np.asarray(traj.Fy, dtype=np.float64)
    if gen.shape[1] <= max(a, b):
        raise ValueError(f"the generated path has only {gen.shape[1]} Y dims; choose axes below that")
    fx_o = np.asarray(manifold.Fx_[u.start:u.stop], dtype=np.float64)
    fx_g = np.asarray(traj.Fx, dtype=np.float64)
    n = min(len(fx_o), len(fx_g))
    rmse_x = float(np.sqrt(np.mean(np.sum((fx_g[:n] - fx_o[:n]) ** 2, axis=1))))
    rmse_y = float(np.sqrt(np.mean(np.sum((gen[:n][:, [a, b]] - orig[:n][:, [a, b]]) ** 2, axis=1))))
    tf = np.asarray(traj.target_frames, dtype=np.int64)
    from engine.recordings.kinematics import has_kinematic_labels

    # a corpus without phone labels is regenerated through its kinematic landmarks: say so, never "phones"
    kinematic = has_kinematic_labels(corpus)
    what = "kinematic landmark" if kinematic else "phone"
    fig = new_figure(width, height or (1.0 if one_column(width) else 0.72) * width)
    ax = fig.subplots()
    lo, = ax.plot(orig[:, a], orig[:, b], "-", color=ORIGINAL, lw=1.3, label="original", zorder=2)
    lg, = ax.plot(gen[:, a], gen[:, b], "-", color=GENERATED, lw=1.3, label="generated (manifold path)", zorder=3)
    lo.set_gid("fig3:original")
    lg.set_gid("fig3:generated")
    handles = [lo, lg]
    tl = list(traj.target_labels)
    if kinematic:
        pal = palette_for(manifold, palette)
        kinds = list(dict.fromkeys(tl))
        for kind in kinds:
            sel = np.asarray([lab == kind for lab in tl])
            mk, = ax.plot(orig[tf[sel], a], orig[tf[sel], b], "o", ms=5.5, mfc=pal.colour("landmark", kind),
                          mec="0.1", mew=0.6, ls="none", label=kind, zorder=5)
            mk.set_gid(f"fig3:landmark:{kind}")
            handles.append(mk)
    else:
        mk, = ax.plot(orig[tf, a], orig[tf, b], "o", ms=6, mfc="none", mec=ORIGINAL, mew=1.1, ls="none",
                      label="phone mid-points (targets)", zorder=5)
        mk.set_gid("fig3:midpoints")
        handles.append(mk)
    ax.set_xlabel(f"Y{a + 1} {ARBITRARY}")
    ax.set_ylabel(f"Y{b + 1} {ARBITRARY}")
    legend_below(fig, handles, ncol=3 if kinematic else 2, gid="fig3:legend")
    text = f" \u201c{u.text}\u201d" if u.text else ""
    ax.set_title(fit_lines(fig, f"Utterance {u.id}{text}\n{len(tf)} {what} targets, {IN_TRAINING}\n"
                           f"RMSE {rmse_x:.3g} {corpus.unit_label} in X (lip shape), {rmse_y:.3g} in this plane "
                           f"{ARBITRARY}", font_pt()))
    notes = []
    if traj.warnings:
        notes.append(f"{len(traj.warnings)} gap(s) not reachable in time; ended at the nearest reachable state")
    note = below(ax, "\n".join(notes)) if notes else None
    left_out = 0
    if label_phones and not kinematic:  # placed last, against the final layout, so that no two labels collide
        args = (ax, orig[tf][:, [a, b]], tl)
        trial: list = []
        left_out = place_labels(*args, fontsize=font_pt(-1), placed_texts=trial)
        if left_out:  # say so under the axes (which changes the layout): place them again against it
            for t in trial:
                t.remove()
            said = notes + [f"{left_out} phone label(s) left out where nothing was free"]
            if note is None:
                note = below(ax, "\n".join(said))
            else:
                note.set_text(fit_lines(fig, "\n".join(said), font_pt(-1)))
            left_out = place_labels(*args, fontsize=font_pt(-1))
            note.set_text(fit_lines(fig, "\n".join(notes + ([f"{left_out} phone label(s) left out where nothing was "
                                                               "free"] if left_out else [])), font_pt(-1)))
    if note is not None:
        note.set_gid("fig3:note")
    fig.lipspace.update(utterance=u.id, target_frames=tf, labels=tl, rmse_x=rmse_x, rmse_y=rmse_y,
                        warnings=list(traj.warnings), labels_left_out=left_out, held_out=False)
    return fig
