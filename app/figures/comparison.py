"""The comparison figure: where and how two levels of a field move differently, for a journal page.

Four panels, from one fitted :class:`engine.comparison.compare.ConditionComparison`:

- (a) the difference view: every frame in the (S, V) plane -- the lip opening and its velocity
  read on the manifold -- coloured by its state's enrichment (log2 occupancy ratio, level b
  over level a) on a diverging, colour-blind-safe scale (:mod:`app.models.comparison`);
  states whose q-value does not pass are faded;
- (b, c) the cluster centre shifts in X (mm per point) and in Y (pooled s.d.s), the clusters with
  the smallest p first, with their bootstrap intervals;
- (d) the dynamics, each as the ratio of level b's value to level a's on a log scale.

Filled markers pass the family's q < alpha; open ones do not. The level names carry their
session-palette colours (kind ``"field:NAME"``). A design that cannot be tested gets no
intervals and says so under the figure.
"""
from __future__ import annotations

import textwrap

import numpy as np
from matplotlib import rc_context, rcParams
from matplotlib.colors import ListedColormap, Normalize
from matplotlib.lines import Line2D

from app.figures.style import font_pt, frame_sv, journal, new_figure, one_column, rasterize_for, require_fitted
from app.models.comparison import PUOR, difference_colours

__all__ = ["make_comparison", "MAX_CLUSTERS", "MIN_TEXT_PT"]

#: clusters shown in panels (b) and (c), smallest p first
MAX_CLUSTERS = 12
#: the smallest text of the figure (points)
MIN_TEXT_PT = 7.0
_TEXT_SIZES = ("font.size", "axes.titlesize", "axes.labelsize", "xtick.labelsize", "ytick.labelsize",
               "legend.fontsize", "figure.titlesize")
#: markers of a comparison that could not be tested
UNTESTED = "0.45"
_SHORT = {"opening speed": "speed", "time in class": "time", "future hemisphere": "future hemisphere",
          "path length per second": "path length per s"}
_TARGET = {"all frames": "all", "while opening": "opening", "while closing": "closing"}


def _marker(ax, y, row, alpha, *, log=False):
    est, lo, hi, q = row["estimate"], row["ci_low"], row["ci_high"], row["q"]
    if np.isfinite(lo) and np.isfinite(hi):
        ax.plot([lo, hi], [y, y], color="k", lw=0.9, solid_capstyle="butt")
    colour, face = ("k", "k" if q < alpha else "white") if np.isfinite(q) else (UNTESTED, UNTESTED)
    if np.isfinite(est) and (not log or est > 0):
        ax.plot([est], [y], marker="o", ms=3.2, color=colour, mfc=face, mew=0.8)


#: ticks a ratio axis chooses from
_RATIO_TICKS = (0.1, 0.2, 0.25, 0.33, 0.5, 0.67, 0.75, 0.8, 0.9, 1.0, 1.1, 1.2, 1.25, 1.33, 1.5, 2.0, 3.0, 4.0, 5.0,
                10.0)


def _ratio_axis(ax):
    """A log axis for ratios, ticked at round ratios inside its range (at most six, 1 always among them)."""
    from matplotlib.ticker import FixedLocator, FuncFormatter, NullLocator

    ax.set_xscale("log")
    values = [x for line in ax.get_lines() for x in np.atleast_1d(line.get_xdata()) if np.isfinite(x) and x > 0]
    lo, hi = (min(values + [1.0]), max(values + [1.0]))
    pad = (hi / lo) ** 0.06
    ax.set_xlim(lo / pad, hi * pad)
    gap = np.log(hi * pad / (lo / pad)) / 5.0  # at most about six ticks, evenly spread on the log axis
    ticks = [1.0]
    for t in sorted((t for t in _RATIO_TICKS if lo / pad <= t <= hi * pad and t != 1.0), key=lambda t: abs(np.log(t))):
        if all(abs(np.log(t / k)) >= gap for k in ticks):
            ticks.append(t)
    ticks.sort()
    ax.xaxis.set_major_locator(FixedLocator(ticks))
    ax.xaxis.set_minor_locator(NullLocator())
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))


def _forest(ax, rows, labels, *, xlabel, alpha, log=False, reference=None):
    for k, r in enumerate(rows):
        _marker(ax, len(rows) - 1 - k, r, alpha, log=log)
    ax.set_yticks(range(len(rows)))
    ax.set_yticklabels(list(reversed(labels)))
    ax.set_ylim(-0.7, len(rows) - 0.3)
    if log:
        _ratio_axis(ax)
    else:
        from matplotlib.ticker import MaxNLocator

        ax.xaxis.set_major_locator(MaxNLocator(nbins=4))
    if reference is not None:
        ax.axvline(reference, color="0.5", lw=0.6, ls=":")
    ax.set_xlabel(xlabel)
    ax.tick_params(axis="y", length=0)
    if not rows:
        ax.text(0.5, 0.5, "nothing to compare", transform=ax.transAxes, ha="center", va="center",
                fontsize=max(MIN_TEXT_PT, font_pt(-1)), color="0.4")


def _dynamics_label(row) -> str:
    measure, target = row["measure"], row["target"]
    if measure == "time in class":
        return "time " + target.replace("accelerating", "acc.").replace("decelerating", "dec.")
    if measure in ("future hemisphere", "path length per second"):
        return _SHORT[measure]
    return f"{_SHORT.get(measure, measure)}, {_TARGET.get(target, target)}"


def _difference_panel(fig, ax, manifold, result, contrast, alpha, level_colour):
    a, b = result.contrasts_[contrast]
    col = difference_colours(result.enrichment_[contrast], result.enrichment_q_[contrast],
                             manifold.states_.labels_, level_a=a, level_b=b, alpha=alpha)
    design = result.designs_[contrast]
    frames = np.flatnonzero(np.isin(manifold.corpus_.utterance_index, design.utterances))
    P = frame_sv(manifold)[frames]
    sig = col.significant[frames]
    order = np.argsort(sig, kind="stable")  # significant states drawn on top
    ax.scatter(P[order, 0], P[order, 1], c=col.rgb[frames][order], s=2.0, lw=0,
               rasterized=rasterize_for(len(frames)))
    sl, vl = manifold.tangent_.sv_labels()
    ax.set_xlabel(sl)
    ax.set_ylabel(vl)
    ax.axhline(0.0, color="0.3", lw=0.5, ls=":")
    cbar = fig.colorbar(_mappable(col.limit), ax=ax, fraction=0.05, pad=0.02, shrink=0.78)
    cbar.set_label(f"log2 occupancy ratio ({b} / {a})")
    cbar.set_ticks([-col.limit, 0.0, col.limit])
    cbar.ax.set_yticklabels([f"{-col.limit:.2g}", "0", f"+{col.limit:.2g}"])
    # the ends named in their levels' palette colours
    cbar.ax.set_title(f"more {b}", color=level_colour(b), fontsize=max(MIN_TEXT_PT, font_pt(-1)))
    cbar.ax.set_xlabel(f"more {a}", color=level_colour(a), fontsize=max(MIN_TEXT_PT, font_pt(-1)))
    n_sig = int(np.sum(np.asarray(result.enrichment_q_[contrast]) < alpha))
    K = result.enrichment_.shape[1]
    ax.set_title(f"(a) where: {n_sig} of {K} states differ (q < {alpha:g})" if col.tested else
                 f"(a) where: {K} states, not tested", loc="left")
    return n_sig


def _mappable(limit):
    from matplotlib.cm import ScalarMappable

    return ScalarMappable(norm=Normalize(-limit, limit), cmap=ListedColormap(list(PUOR)))


@journal
def make_comparison(manifold, result, *, contrast: int = 0, palette=None, width=None, height: float | None = None,
                    max_clusters: int = MAX_CLUSTERS):
    """The comparison figure of contrast ``contrast`` of ``result`` (module docstring); every text at least
    :data:`MIN_TEXT_PT` points.

    Parameters
    ----------
    manifold : engine.manifold.model.Manifold
        The manifold the comparison was fitted on.
    result : engine.comparison.compare.ConditionComparison, fitted
    contrast : int
        Index into ``result.contrasts_``.
    palette : app.models.palette.SessionPalette or None
        Colours of the levels (default: a palette ranking the two levels by utterances).
    width, height : float or None
        Inches (:func:`app.figures.style.journal`).
    max_clusters : int
        Clusters shown in (b) and (c).
    """
    with rc_context({k: max(MIN_TEXT_PT, float(rcParams[k])) for k in _TEXT_SIZES}):
        return _make(manifold, result, contrast=contrast, palette=palette, width=width, height=height,
                     max_clusters=max_clusters)


def _make(manifold, result, *, contrast, palette, width, height, max_clusters):
    require_fitted(manifold, "tangent_", "states_")
    if not 0 <= contrast < len(result.contrasts_):
        raise ValueError(f"contrast={contrast}: the comparison has {len(result.contrasts_)} contrast(s)")
    from app.models.palette import SessionPalette

    design = result.designs_[contrast]
    a, b = result.contrasts_[contrast]
    field = f"field:{design.by}"
    if palette is None:
        na, nb = design.n_units
        palette = SessionPalette(ranking={field: [a, b] if na >= nb else [b, a]})

    def level_colour(lv):
        return palette.colour(field, lv)

    alpha = float(result.alpha)
    narrow = one_column(width)
    note = f"{design.describe()}." if design.testable else f"descriptive only: {design.reason}."
    n_clusters = len({r["target"] for r in result.table(family="cluster", contrast=contrast)})
    if n_clusters > max_clusters:
        note += (f" Clusters: the {max_clusters} of {n_clusters} with the smallest p" if design.testable else
                 f" Clusters: the {max_clusters} of {n_clusters} that moved most") + " shown."
    size = max(MIN_TEXT_PT, font_pt(-1))
    note = textwrap.fill(note, max(30, int(0.92 * width * 72 / (0.55 * size))))
    height = height or (2.2 if narrow else 0.8) * width
    foot_in = ((2 if narrow else 1) * 1.7 + (note.count("\n") + 1) * 1.35 + 1.0) * size / 72
    fig = new_figure(width, height + foot_in)
    # one subfigure per row: each row lays itself out (long dynamics labels do not squeeze the map)
    if narrow:
        top, mid, dyn_row, foot = fig.subfigures(4, 1, height_ratios=[0.4 * height, 0.32 * height,
                                                                       0.28 * height, foot_in])
        ax_a, ax_d = top.subplots(), dyn_row.subplots()
        ax_b, ax_c = mid.subplots(1, 2, sharey=True)
    else:
        top, mid, foot = fig.subfigures(3, 1, height_ratios=[0.55 * height, 0.45 * height, foot_in])
        left, right = top.subfigures(1, 2, width_ratios=[1.1, 1.0])
        ax_a, ax_d = left.subplots(), right.subplots()
        ax_b, ax_c = mid.subplots(1, 2, sharey=True)
    n_sig = _difference_panel(ax_a.figure, ax_a, manifold, result, contrast, alpha, level_colour)

    clusters = result.table(family="cluster", contrast=contrast)
    shifts = {s: {r["target"]: r for r in clusters if r["measure"] == "centre shift" and r["space"] == s}
              for s in ("X", "Y")}
    order = sorted(shifts["X"], key=lambda t: (min(shifts["X"][t]["p"], shifts["Y"][t]["p"])
                                               if design.testable else -shifts["X"][t]["estimate"], t))
    shown = order[:max_clusters]
    unit_x = next(iter(shifts["X"].values()))["unit"] if shifts["X"] else "mm per point (RMS)"
    unit_x = unit_x.replace(" per point (RMS)", " per point, RMS")
    _forest(ax_b, [shifts["X"][t] for t in shown], shown, xlabel=f"shift ({unit_x})", alpha=alpha)
    _forest(ax_c, [shifts["Y"][t] for t in shown], shown, xlabel="shift (pooled s.d.)", alpha=alpha)
    ax_c.tick_params(axis="y", labelleft=False)
    kind = "landmark" if result.cluster_kind_ == "kinematic" else "phone"
    ax_b.set_title(f"(b) {kind}s: X (shape)" if narrow else f"(b) {kind} centres in X (shape)", loc="left")
    ax_c.set_title("(c) Y (dynamics)" if narrow else "(c) in Y (shape with dynamics)", loc="left")

    dyn = result.table(family="dynamics", contrast=contrast)
    labels = [_dynamics_label(r) for r in dyn]
    _forest(ax_d, dyn, labels, xlabel=f"ratio {b} / {a} (log scale)", alpha=alpha, log=True, reference=1.0)
    ax_d.set_title("(d) dynamics on the manifold", loc="left")

    handles = [Line2D([], [], ls="", marker="s", ms=4, color=level_colour(lv),
                      label=f"{lv}: {n} {design.unit_name}{'s' if n != 1 else ''}")
               for lv, n in zip((a, b), design.n_units)]
    if design.testable:
        handles += [Line2D([], [], ls="", marker="o", ms=3.2, color="k", label=f"q < {alpha:g}"),
                    Line2D([], [], ls="", marker="o", ms=3.2, color="k", mfc="white", label="not significant")]
    else:
        handles.append(Line2D([], [], ls="", marker="o", ms=3.2, color=UNTESTED, label="not tested"))
    foot.legend(handles=handles, loc="upper center", ncol=2 if narrow else 4, frameon=False,
                bbox_to_anchor=(0.5, 1.0), borderaxespad=0.2)
    foot.text(0.5, 0.02, note, ha="center", va="bottom", fontsize=size, color="0.25")
    fig.suptitle(f"{design.by}: {b} against {a}", fontsize=font_pt(1))
    fig.lipspace.update(contrast=(a, b), design=design.describe(), testable=design.testable,
                        significant_states=n_sig, clusters_shown=list(shown),
                        significant_rows=len(result.significant(contrast=contrast)))
    return fig
