"""Paper fig. 4: bilabial phone clusters on the manifold."""
from __future__ import annotations

import numpy as np
from matplotlib import patheffects

from app.figures.colours import lightness, palette_for
from app.figures.style import (
    ARBITRARY,
    below,
    frame_sv,
    journal,
    legend_below,
    new_figure,
    one_column,
    require_fitted,
    y3,
)

__all__ = ["make_fig4", "ellipse_points"]

_OUTLINE = [patheffects.withStroke(linewidth=2.6, foreground="0.15")]
#: a phone colour this light (CIELAB L*) gets a dark outline on its ellipse, to stand out on white
LIGHT = 75.0


def ellipse_points(mean, cov, n_sd: float = 2.0, n_points: int = 100) -> np.ndarray:
    """Outline (n_points, 2) of the ellipse at Mahalanobis distance ``n_sd`` of a 2-D Gaussian."""
    w, V = np.linalg.eigh(np.asarray(cov, dtype=np.float64))
    L = V * np.sqrt(np.clip(w, 0.0, None))
    t = np.linspace(0.0, 2 * np.pi, int(n_points), endpoint=False)
    return np.asarray(mean, dtype=np.float64) + float(n_sd) * np.column_stack([np.cos(t), np.sin(t)]) @ L.T


@journal
def make_fig4(manifold, *, phones=("b", "p", "m"), colours=None, axes="sv", n_sd: float = 2.0,
              min_count: int = 3, width=None, height: float | None = None, palette=None):
    """Fig. 4: mid-points of /b/, /p/ and /m/ with 2-s.d. ellipses, in the session palette's phone colours.

    Each phone's mid-point frames (:class:`engine.manifold.clusters.PhoneClusters`; labels are
    matched through :func:`engine.phonetics.phonesets.normalize`, so ``B``/``P``/``M`` of an
    ARPAbet corpus are found), their ``n_sd`` ellipse and their mean (square).
    Phones the corpus lacks (or has fewer than ``min_count`` mid-points of) are
    skipped with a note on the figure; with none of them found, ValueError (no empty figure).

    Parameters
    ----------
    phones : sequence of str, default=("b", "p", "m")
    colours : sequence of colours, optional
        One per phone; default the session palette's (``palette.colour("phone", label)``, the
        colours the window gives these phones).
    axes : "sv" or (int, int), default="sv"
        ``"sv"``: the (S, V) plane, the opening (x) and its velocity read on the
        manifold (y), where the zero-velocity plane is the dotted line V = 0 and the
        opening half of the cycle lies above it; ellipses are the 2-s.d. ellipses of
        the members' (S, V). A pair of Y dims (0-based) shows those dims, with
        :meth:`PhoneClusters.ellipse` and the plane's trace.
    palette : app.models.palette.SessionPalette, optional
        The session's palette (default: the corpus's own).
    """
    require_fitted(manifold, "tangent_")
    from engine.manifold.clusters import PhoneClusters

    tan = manifold.tangent_
    pc = PhoneClusters.from_manifold(manifold, n_dims=min(3, manifold.Fy_.shape[1]), min_count=min_count)
    if colours is None:
        pal = palette_for(manifold, palette)
        colours = [pal.colour("phone", _corpus_label(pc, p)) for p in phones]
    if len(colours) != len(phones):
        raise ValueError(f"{len(colours)} colours for {len(phones)} phones; give one colour per phone")
    sv = isinstance(axes, str)
    if sv and axes != "sv":
        raise ValueError(f"axes={axes!r}: use 'sv' or a pair of Y dims such as (0, 1)")
    Y = y3(manifold)
    if sv:
        P = frame_sv(manifold)
    else:
        a, b = (int(v) for v in axes)
        if not (0 <= a < 3 and 0 <= b < 3 and a != b):
            raise ValueError(f"axes={tuple(axes)}: need two different Y dims in 0..2")
    fig = new_figure(width, height or (1.0 if one_column(width) else 0.72) * width)
    ax = fig.subplots()
    found, missing = {}, []
    for phone, col in zip(phones, colours):
        try:
            i = pc.index(phone)
        except ValueError:
            missing.append(phone)
            continue
        idx = pc.members(phone)
        if sv:
            pts = P[idx]
            mean = pts.mean(axis=0)
            cov = np.atleast_2d(np.cov(pts, rowvar=False))
            ell = ellipse_points(mean, cov, n_sd)
        else:
            pts = Y[idx][:, [a, b]]
            mean = pc.means_[i][[a, b]]
            ell = pc.ellipse(phone, axes=(a, b), n_sd=n_sd)
        frac = float(pc.opening_fraction_[i])
        label = f"/{pc.phones_[i]}/  n={len(idx)}, {100 * frac:.0f}% opening"
        sc = ax.scatter(pts[:, 0], pts[:, 1], s=14, color=col, edgecolors="0.15", linewidths=0.4,
                        label=label, zorder=3)
        sc.set_gid(f"fig4:points:{phone}")
        closed = np.vstack([ell, ell[:1]])
        line, = ax.plot(closed[:, 0], closed[:, 1], "-", color=col, lw=1.6, zorder=4,
                        path_effects=_OUTLINE if _light(col) else None)
        line.set_gid(f"fig4:ellipse:{phone}")
        sq, = ax.plot(*mean, "s", ms=10, mfc=col, mec="k", mew=1.2, zorder=5)
        sq.set_gid(f"fig4:mean:{phone}")
        found[phone] = {"label": pc.phones_[i], "count": int(len(idx)), "opening_fraction": frac,
                        "mean": np.asarray(mean), "cov": None if not sv else cov}
    if not found:  # an empty figure is no figure
        raise ValueError(f"none of {', '.join(f'/{p}/' for p in phones)} has {min_count} or more mid-points in "
                         f"{manifold.corpus_.name} (phones with clusters: {' '.join(pc.phones_) or 'none'}); "
                         "choose phones the corpus has")
    if sv:
        zl = ax.axhline(0.0, color="k", ls=":", lw=1.0, label="zero velocity")
        ax.set_xlabel(tan.sv_labels()[0])
        ax.set_ylabel(tan.sv_labels()[1])
    else:
        from app.figures.style import plane_trace

        zl = plane_trace(ax, tan, (a, b), Y[np.concatenate([pc.members(p) for p in found])] if found else Y)
        ax.set_xlabel(f"$Y_{a + 1}$ {ARBITRARY}")
        ax.set_ylabel(f"$Y_{b + 1}$ {ARBITRARY}")
        ax.autoscale(True)
        ax.relim()
        ax.autoscale_view()
    if zl is not None:
        zl.set_gid("fig4:zero-velocity")
    handles, _ = ax.get_legend_handles_labels()
    legend_below(fig, handles, ncol=2, gid="fig4:legend")
    names = ", ".join(f"/{p}/" for p in phones)
    ax.set_title(f"Clusters of {names} mid-points ({n_sd:g} s.d. ellipses, squares: means)")
    notes = []
    if missing:
        notes.append("not in this corpus (or fewer than "
                     f"{min_count} mid-points): " + ", ".join(f"/{p}/" for p in missing))
    sep = _separation_note(pc, [p for p in phones if p in found])
    if sep:
        notes.append(sep)
    if notes:
        txt = below(ax, "\n".join(notes))
        txt.set_gid("fig4:note")
    fig.lipspace.update(found=found, missing=missing)
    return fig


def _corpus_label(pc, phone) -> str:
    """The corpus's own label of ``phone`` (``B`` for ``b`` in an ARPAbet corpus): the level the palette colours."""
    try:
        return str(pc.phones_[pc.index(phone)])
    except ValueError:
        return str(phone)


def _light(colour) -> bool:
    from matplotlib.colors import to_rgb

    return bool(lightness(to_rgb(colour)) > LIGHT)


def _separation_note(pc, phones) -> str:
    """Bhattacharyya separations with dynamics (Y) and shape only (X) for each pair."""
    parts = []
    for k, p in enumerate(phones):
        for q in phones[k + 1:]:
            try:
                y, x = pc.separation(p, q, "y"), pc.separation(p, q, "x")
            except ValueError:
                continue
            parts.append(f"/{p}/–/{q}/ Y {y:.2f}, X {x:.2f}")
    return ("Bhattacharyya separation: " + "; ".join(parts)) if parts else ""
