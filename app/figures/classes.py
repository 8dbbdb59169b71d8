"""The four tangent classes of the frames: their proportions and where they lie in the (S, V) plane."""
from __future__ import annotations

import numpy as np
from matplotlib.lines import Line2D

from app.figures.colours import palette_for
from app.figures.style import (
    below,
    font_pt,
    frame_sv,
    journal,
    legend_below,
    marker_size,
    new_figure,
    one_column,
    rasterize_for,
    require_fitted,
)

__all__ = ["make_classes", "class_colours"]


def class_colours(manifold, palette=None) -> list:
    """The colours of the tangent classes 0..3 (:data:`engine.manifold.tangent.CLASS_NAMES`), the session palette's
    (``palette.colour("class", label)``)."""
    from app.models.palette import CLASS_LABELS

    pal = palette_for(manifold, palette)
    return [pal.colour("class", label) for label in CLASS_LABELS]


@journal
def make_classes(manifold, *, width=None, height: float | None = None, palette=None):
    """The four tangent classes: proportions (bars) and where they lie in the (S, V) plane.

    Side by side at two-column width, stacked on one column; the classes' legend below. The classes'
    colours are the session palette's (:func:`class_colours`): opening warm, closing cool,
    accelerating dark, decelerating light.
    """
    require_fitted(manifold, "tangent_")
    tan = manifold.tangent_
    names = list(tan.CLASS_NAMES)
    cls = np.asarray(tan.classes_)
    valid = cls >= 0
    counts = np.bincount(cls[valid], minlength=len(names))[: len(names)]
    frac = counts / max(counts.sum(), 1)
    colours = class_colours(manifold, palette)
    narrow = one_column(width)
    fig = new_figure(width, height or (1.55 if narrow else 0.45) * width)
    ax, ax2 = fig.subplots(2, 1, height_ratios=(1, 1.3)) if narrow else fig.subplots(1, 2, width_ratios=(1, 1.3))
    bars = ax.bar(np.arange(len(names)), 100 * frac, color=colours[: len(names)])
    for patch in bars:
        patch.set_gid("classes:bars")
    for k, f in enumerate(frac):
        ax.annotate(f"{100 * f:.1f}%", xy=(k, 100 * f), xytext=(0, 2), textcoords="offset points",
                    ha="center", fontsize=font_pt(-1))
    ax.set_xticks(np.arange(len(names)), [n.replace("/", "/\n") for n in names])
    ax.set_ylabel("% of frames")
    ax.set_ylim(0, max(100 * frac.max() * 1.2, 1))
    ax.set_title("Tangent classes (frames with a step)")
    truth = _true_agreement(manifold)
    if truth is not None:
        below(ax, f"true aperture: opening {100 * truth.opening:.1f}%, accelerating "
              f"{100 * truth.accelerating:.1f}%\n(trivial rule {100 * truth.trivial_opening:.1f}%, "
              f"{100 * truth.trivial_accelerating:.1f}%)")
    P = frame_sv(manifold)
    sel = np.flatnonzero(valid)
    sel = sel[np.random.default_rng(0).permutation(len(sel))]   # no class hides another
    sc = ax2.scatter(P[sel, 0], P[sel, 1], s=marker_size(len(P)), c=np.asarray(colours)[cls[sel]],
                     linewidths=0, rasterized=rasterize_for(len(P)))
    sc.set_gid("classes:points")
    ax2.axhline(0, color="k", ls=":", lw=1.0)
    ax2.set_xlabel(tan.sv_labels()[0])
    ax2.set_ylabel(tan.sv_labels()[1])
    handles = [Line2D([], [], ls="none", marker="o", ms=5, color=colours[k], label=n)
               for k, n in enumerate(names)]
    legend_below(fig, handles, gid="classes:legend")
    fig.lipspace.update(proportions=dict(zip(names, frac.tolist())),
                        true_agreement=None if truth is None else truth.opening,
                        opening_on_positive_v=float(np.mean(P[valid & (cls <= 1), 1] > 0))
                        if (valid & (cls <= 1)).any() else float("nan"))
    return fig


def _true_agreement(manifold):
    """The classes against the synthetic talker's true aperture (engine.manifold.class_agreement), or None."""
    lat = getattr(manifold.corpus_, "latent", {}) or {}
    if "aperture" not in lat:
        return None
    from engine.manifold.class_agreement import class_agreement
    from engine.recordings.kinematics import lip_aperture

    tan = manifold.tangent_
    return class_agreement(tan.opening_, tan.accelerating_, lat["aperture"], manifold.corpus_.bounds,
                           measured=lip_aperture(manifold.corpus_))
