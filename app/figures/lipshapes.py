"""Lip shapes on a figure panel, drawn as :class:`app.models.lip_drawing.LipDrawing` says.

A measured surface is drawn as painter-sorted, Lambert-shaded triangles; sensors as
markers joined by straight segments, each labelled, with the lip aperture as a dimension
line labelled with its length; bare points as markers. Every lip-shape panel has equal
aspect and no axes: a scale bar in the corpus's unit gives the size, and a profile
(midsagittal) panel shows which way the face looks.
"""
from __future__ import annotations

import numpy as np
from matplotlib.collections import LineCollection, PolyCollection
from matplotlib.colors import Normalize, to_rgba

from app.figures.style import font_pt, nice_length, rasterize_for

__all__ = ["talker_frame", "shape_points", "shape_view", "drawing_for", "draw_frame", "shared_limits", "scale_bar",
           "face_direction", "SENSOR_COLOUR", "OTHER_SENSOR_COLOUR"]

#: markers of lip sensors without a value to show, and of jaw / reference / tongue sensors
SENSOR_COLOUR = "0.15"
OTHER_SENSOR_COLOUR = "0.55"
#: the segments joining the lip sensors
SEGMENT_COLOUR = "0.3"
#: the aperture's dimension line
APERTURE_COLOUR = "0.2"
#: distance of a sensor's label from its marker (points)
LABEL_OFFSET_PT = 4.5


def talker_frame(manifold):
    """The talker's frame of the manifold's corpus (:func:`engine.recordings.orientation.anatomical_frame`)."""
    from engine.recordings.orientation import anatomical_frame

    return anatomical_frame(manifold.corpus_, manifold.shape_.mean_)


def shape_points(manifold, frame_row, frame=None) -> np.ndarray:
    """One frame row (C,) as points (V, 3) in the talker's view coordinates (x the talker's left, y up, z
    towards the viewer; 2-D: x forward, y up, z = 0), ``frame`` as :func:`talker_frame` gives it."""
    from engine.recordings.corpus import frame_points

    frame = talker_frame(manifold) if frame is None else frame
    row = frame.view_frames(np.asarray(frame_row, np.float64)[None])[0]
    P = frame_points(row, manifold.corpus_.dims).astype(np.float64)
    return P


def shape_view(manifold, view, frame=None):
    """``view`` if given; else (0, 1), the front view (profile for 2-D) of :func:`shape_points`, when the
    talker's frame is known, and None (the axes of the widest spread) when it is not."""
    if view is not None:
        return view
    frame = talker_frame(manifold) if frame is None else frame
    return (0, 1) if frame.source != "none" else None


def drawing_for(manifold, frame=None):
    """The :class:`app.models.lip_drawing.LipDrawing` of the manifold's corpus, sensors ordered on its mean shape."""
    from app.models.lip_drawing import lip_drawing

    frame = talker_frame(manifold) if frame is None else frame
    return lip_drawing(manifold.corpus_, shape_points(manifold, manifold.shape_.mean_, frame), frame=frame)


def _axes_of(points, view) -> tuple[int, int, int | None]:
    """(horizontal, vertical, depth) axes of a panel: ``view``'s, or the widest spread's (width, height, depth)."""
    P = np.asarray(points, np.float64)
    if view is not None:
        h, v = int(view[0]), int(view[1])
        rest = [k for k in range(P.shape[1]) if k not in (h, v)]
        return h, v, (rest[0] if rest and np.ptp(P[:, rest[0]]) > 0 else None)
    spread = np.ptp(P, axis=0)
    order = [int(k) for k in np.argsort(-spread, kind="stable")]
    return order[0], order[1], (order[2] if len(order) > 2 and spread[order[2]] > 0 else None)


def _colours(values, norm, cmap):
    if values is None:
        return None
    norm = norm or Normalize(float(np.min(values)), float(np.max(values)) or 1.0)
    return cmap(norm(np.asarray(values, dtype=np.float64)))


def _panel(ax):
    """A lip-shape panel: equal aspect, no ticks or spines (a scale bar gives the size)."""
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for sp in ax.spines.values():
        sp.set_visible(False)


def _surface(ax, P, faces, h, v, dep, cols, color, gid):
    F = np.asarray(faces)
    tri = P[F]                                         # (T, 3, 3)
    nrm = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-12)
    view_dir = np.cross(np.eye(3)[h], np.eye(3)[v])   # towards the viewer
    shade = 0.55 + 0.45 * np.abs(nrm @ view_dir)
    depth = tri.mean(axis=1) @ view_dir
    order = np.argsort(depth, kind="stable")          # far first
    base = cols[F].mean(axis=1) if cols is not None else np.tile(to_rgba(color), (len(F), 1))
    fc = base.copy()
    fc[:, :3] *= shade[:, None]
    pc = PolyCollection(tri[order][:, :, [h, v]], facecolors=fc[order], edgecolors="none", linewidths=0,
                        antialiased=False, rasterized=rasterize_for(len(F)), zorder=1)
    ax.add_collection(pc)
    ax.update_datalim(P[:, [h, v]])
    ax.autoscale_view()
    if gid:
        pc.set_gid(gid)
    return pc


def draw_frame(ax, drawing, points, *, values=None, norm=None, cmap=None, color=SENSOR_COLOUR, labels: bool = True,
               aperture: bool = True, view=None, gid=None) -> dict:
    """Draw one lip frame (V, 3, view coordinates) as ``drawing`` says on ``ax``.

    Parameters
    ----------
    drawing : app.models.lip_drawing.LipDrawing
    points : ndarray of shape (V, 3)
    values, norm, cmap
        Per-point values coloured through ``cmap`` / ``norm`` (the lip sensors' markers, or the
        surface); without, lip sensors are ``color`` and the surface a light grey.
    labels : bool
        Write each sensor's label beside it.
    aperture : bool
        Draw the aperture's dimension line with its length.
    gid : str
        Prefix of the artists' gids: ``<gid>`` (the markers or the surface), ``<gid>:segments``,
        ``<gid>:aperture``, ``<gid>:aperture:label``, ``<gid>:label``.

    Returns
    -------
    dict
        ``{"markers", "segments", "aperture", "aperture_value", "labels", "label_of"}`` (absent parts None;
        ``label_of`` maps a point to its label).
    """
    P = np.asarray(points, np.float64)
    h, v, dep = _axes_of(P, view)
    cols = _colours(values, norm, cmap)
    out = {"markers": None, "segments": None, "aperture": None, "aperture_value": None, "labels": [], "label_of": {}}
    _panel(ax)
    if drawing.kind == "surface":
        out["markers"] = _surface(ax, P, drawing.faces, h, v, dep, cols, "0.78" if cols is None else color, gid)
    else:
        xy = P[:, [h, v]]
        if len(drawing.segments):
            seg = LineCollection(xy[drawing.segments], colors=[SEGMENT_COLOUR], linewidths=1.1,
                                 zorder=2, capstyle="round")
            ax.add_collection(seg)
            if gid:
                seg.set_gid(f"{gid}:segments")
            out["segments"] = seg
        lip = drawing.lip
        mc = np.tile(to_rgba(color), (len(P), 1)) if cols is None else cols
        mc[~lip] = to_rgba(OTHER_SENSOR_COLOUR)
        big = drawing.kind == "sensors"
        s_lip = 22.0 if big else 5.0
        m1 = ax.scatter(xy[lip, 0], xy[lip, 1], s=s_lip, c=mc[lip], edgecolors="0.1" if big else "none",
                        linewidths=0.5 if big else 0, zorder=4, rasterized=rasterize_for(len(P)))
        if (~lip).any():
            m2 = ax.scatter(xy[~lip, 0], xy[~lip, 1], s=s_lip, c=mc[~lip], marker="s",
                            edgecolors="0.1" if big else "none", linewidths=0.5 if big else 0, zorder=4)
            if gid:
                m2.set_gid(f"{gid}:other")
        if gid:
            m1.set_gid(gid)
        out["markers"] = m1
        ax.update_datalim(xy)
        ax.autoscale_view()
        if labels and drawing.kind == "sensors":
            out["label_of"] = _sensor_labels(ax, xy, drawing.labels, gid)
            out["labels"] = list(out["label_of"].values())
    if aperture and drawing.has_aperture:
        top, bottom, value = drawing.aperture(P)
        low = int(np.argmin(P[:, v]))
        # under the lowest point, and under its label when that one hangs below it
        hangs = low in out["label_of"] and out["label_of"][low].get_va() == "top"
        clear = 3.0 + (1.3 * font_pt(-1) + LABEL_OFFSET_PT if hangs else 0.0)
        rest = np.setdiff1d(np.arange(len(P)), np.r_[drawing.upper, drawing.lower])
        out["aperture"] = _dimension_line(ax, top[[h, v]], bottom[[h, v]], drawing.aperture_text(value), gid,
                                          others=P[rest][:, [h, v]] if drawing.kind == "sensors" else None,
                                          below_y=float(P[:, v].min()), clear_pt=clear)
        out["aperture_value"] = value
    return out


def _sensor_labels(ax, xy, labels, gid) -> dict:
    """Each sensor's label beside it, pushed away from the sensors' centroid (outside the mouth): ``{point: text}``."""
    c = xy.mean(axis=0)
    out = {}
    for i, ((x, y), text) in enumerate(zip(xy, labels)):
        if not text:
            continue
        d = np.array([x - c[0], y - c[1]])
        n = np.linalg.norm(d)
        d = d / n if n > 1e-12 else np.array([0.0, 1.0])
        # the side the point lies on decides the alignment: labels never cross their own marker
        ha = "left" if d[0] > 0.38 else "right" if d[0] < -0.38 else "center"
        va = "bottom" if d[1] > 0.38 else "top" if d[1] < -0.38 else "center"
        t = ax.annotate(text, xy=(x, y), xytext=(LABEL_OFFSET_PT * d[0], LABEL_OFFSET_PT * d[1]),
                        textcoords="offset points", ha=ha, va=va,
                        fontsize=font_pt(-1), color="0.2", zorder=5, annotation_clip=False)
        if gid:
            t.set_gid(f"{gid}:label")
        out[i] = t
    return out


def _dimension_line(ax, a, b, text, gid, *, others, below_y, clear_pt):
    """A dashed dimension line from ``a`` to ``b`` (2-D data coordinates) with end ticks, and ``text`` where no
    sensor is: beside the line's middle on the side no other sensor (``others``, (k, 2)) lies on, else (and
    always on a surface, ``others`` None) under the shape: below ``below_y``, ``clear_pt`` points lower still,
    clear of a sensor's label."""
    a, b = np.asarray(a, float), np.asarray(b, float)
    line, = ax.plot([a[0], b[0]], [a[1], b[1]], color=APERTURE_COLOUR, lw=0.7, ls=(0, (2.5, 1.5)), zorder=3,
                    marker="_", ms=5, mew=0.8)
    mid = 0.5 * (a + b)
    span = max(float(np.hypot(*(b - a))), 1e-9)
    side = None
    if others is not None:  # sensors: beside the line on a side no other sensor lies on, when there is one
        off = others[:, 0] - mid[0]
        side = np.sign(off[np.abs(off) > 0.05 * span])
    if side is not None and abs(b[1] - a[1]) >= abs(b[0] - a[0]) and not (np.any(side > 0) and np.any(side < 0)):
        right = not np.any(side > 0)
        t = ax.annotate(text, xy=mid, xytext=(4 if right else -4, 0), textcoords="offset points",
                        ha="left" if right else "right", va="center", fontsize=font_pt(-1), color=APERTURE_COLOUR,
                        zorder=5, annotation_clip=False)
    else:
        t = ax.annotate(text, xy=(mid[0], below_y), xytext=(0, -clear_pt), textcoords="offset points",
                        ha="center", va="top", fontsize=font_pt(-1), color=APERTURE_COLOUR, zorder=5,
                        annotation_clip=False)
    if gid:
        line.set_gid(f"{gid}:aperture")
        t.set_gid(f"{gid}:aperture:label")
    return line


def face_direction(ax, drawing, *, gid=None):
    """On a profile panel whose face direction is known: an arrow in its lower right corner (the scale bar
    takes the lower left), pointing where the face looks, "front" written over it (nothing otherwise).
    Returns the arrow's annotation or None."""
    if drawing.view != "profile" or drawing.forward is None:
        return None
    sign = 1.0 if float(drawing.forward[0]) >= 0 else -1.0
    x0, x1 = (0.66, 0.94) if sign > 0 else (0.94, 0.66)
    ann = ax.annotate("", xy=(x1, 0.06), xytext=(x0, 0.06), xycoords="axes fraction", textcoords="axes fraction",
                      arrowprops=dict(arrowstyle="-|>,head_length=0.35,head_width=0.18", color="0.25", lw=0.8,
                                      shrinkA=0, shrinkB=0))
    t = ax.annotate("front", xy=(0.8, 0.06), xycoords="axes fraction", xytext=(0, 1.5), textcoords="offset points",
                    ha="center", va="bottom", fontsize=font_pt(-1), color="0.25")
    if gid:
        ann.set_gid(gid)
        t.set_gid(f"{gid}:label")
    return ann


def shared_limits(axs, shapes, *, view=None, margin=0.18, below=0.0, above=0.0):
    """Equal limits on every panel of ``axs`` holding all ``shapes`` (list of (V, 3) view points) with
    ``margin`` of the larger extent on every side (room for the sensors' labels), ``below`` more at the
    bottom (a :func:`scale_bar`, a profile's :func:`face_direction`) and ``above`` more at the top; a panel is
    never narrower than it is tall."""
    pts = []
    for P in shapes:
        P = np.asarray(P, np.float64)
        h, v, _ = _axes_of(P, view)
        pts.append(P[:, [h, v]])
    allp = np.concatenate(pts)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    span = float(max(np.ptp(allp, axis=0).max(), 1e-9))
    pad = margin * span
    y0, y1 = lo[1] - pad - below * span, hi[1] + pad + above * span
    # never narrower than tall (a profile of two lip sensors is a vertical line): room for labels beside it
    half = 0.5 * max(hi[0] - lo[0] + 2 * pad, y1 - y0)
    cx = 0.5 * (lo[0] + hi[0])
    for ax in axs:
        ax.set_xlim(cx - half, cx + half)
        ax.set_ylim(y0, y1)


def scale_bar(ax, unit: str, *, length=None, gid=None):
    """A horizontal scale bar in a corner of a lip-shape panel, labelled with its length and ``unit``.

    Call after the panel's limits are final; :func:`clear_scale_bar` then moves it to a corner where it
    meets nothing. Returns the bar's Line2D.
    """
    x0, x1 = ax.get_xlim()
    L = nice_length(x1 - x0) if length is None else float(length)
    line, = ax.plot([0.0, L], [0.0, 0.0], color="0.15", lw=1.2, solid_capstyle="butt")
    t = ax.annotate(f"{L:g} {unit}", xy=(L / 2, 0.0), xytext=(0, 1.5), textcoords="offset points", ha="center",
                    va="bottom", fontsize=font_pt(-1), color="0.15")
    line.lipspace_label = t
    _place_bar(ax, line, BAR_CORNERS[0])
    if gid:
        line.set_gid(gid)
        t.set_gid(f"{gid}:label")
    return line


#: where a scale bar may go, in the order tried: (x, y) of its left end as fractions of the panel (the label
#: sits above the bar)
BAR_CORNERS = ((0.06, 0.06), (0.06, 0.84), (0.94, 0.06), (0.94, 0.84))


def _place_bar(ax, line, corner):
    """Put a :func:`scale_bar` in ``corner`` of its panel's current limits (right corners: its right end)."""
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    L = float(np.ptp(line.get_xdata()))
    fx, fy = corner
    bx = x0 + fx * (x1 - x0) - (L if fx > 0.5 else 0.0)
    by = y0 + fy * (y1 - y0)
    line.set_data([bx, bx + L], [by, by])
    line.lipspace_label.xy = (bx + L / 2, by)


def key_cell(ax, unit: str, drawing, *, gid=None):
    """A cell of its own beside lip-shape panels of the same size and limits: a scale bar (in ``unit``) in its
    middle and, for a profile, the face direction under it. Returns the bar."""
    ax.set_aspect("equal")
    ax.set_axis_off()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    L = nice_length(x1 - x0)
    cx, cy = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    line, = ax.plot([cx - L / 2, cx + L / 2], [cy, cy], color="0.15", lw=1.2, solid_capstyle="butt")
    t = ax.annotate(f"{L:g} {unit}", xy=(cx, cy), xytext=(0, 1.5), textcoords="offset points", ha="center",
                    va="bottom", fontsize=font_pt(-1), color="0.15")
    if gid:
        line.set_gid(f"{gid}:scale")
        t.set_gid(f"{gid}:scale:label")
    if drawing.view == "profile" and drawing.forward is not None:
        sign = 1.0 if float(drawing.forward[0]) >= 0 else -1.0
        a, b = (cx - L / 2, cx + L / 2) if sign > 0 else (cx + L / 2, cx - L / 2)
        yy = cy - 0.22 * (y1 - y0)
        ann = ax.annotate("", xy=(b, yy), xytext=(a, yy), arrowprops=dict(
            arrowstyle="-|>,head_length=0.35,head_width=0.18", color="0.25", lw=0.8, shrinkA=0, shrinkB=0))
        ft = ax.annotate("front", xy=(cx, yy), xytext=(0, -2.5), textcoords="offset points", ha="center",
                         va="top", fontsize=font_pt(-1), color="0.25")
        if gid:
            ann.set_gid(f"{gid}:front")
            ft.set_gid(f"{gid}:front:label")
    return line


def _drawn_boxes(ax, *, exclude=None) -> list:
    """Display boxes of what a lip-shape panel draws: each sensor (its marker), each segment and line (its
    end points' box), the surface (its extent)."""
    from matplotlib.collections import LineCollection, PathCollection
    from matplotlib.transforms import Bbox

    half = 4.0 * ax.figure.dpi / 72.0
    out = []
    for c in ax.collections:
        if isinstance(c, PathCollection):
            for x, y in ax.transData.transform(np.asarray(c.get_offsets(), float)):
                out.append(Bbox.from_extents(x - half, y - half, x + half, y + half))
        elif isinstance(c, LineCollection):
            for seg in c.get_segments():
                out.append(Bbox.from_extents(*ax.transData.transform(seg).min(0), *ax.transData.transform(seg).max(0)))
        else:  # a surface
            pts = np.concatenate([p.vertices for p in c.get_paths()]) if c.get_paths() else np.zeros((0, 2))
            if len(pts):
                d = ax.transData.transform(pts)
                out.append(Bbox.from_extents(*d.min(0), *d.max(0)))
    for line in ax.get_lines():
        if line is not exclude and len(line.get_xydata()):
            d = ax.transData.transform(np.asarray(line.get_xydata(), float))
            out.append(Bbox.from_extents(*d.min(0), *d.max(0)).padded(half / 2))
    return out


def clear_scale_bar(fig, axs, bar, *, passes: int = 3) -> None:
    """Move the scale bar to the first corner of its panel (:data:`BAR_CORNERS`) where it meets no text and
    no point drawn there (a sensor, its label, the aperture's value, the face direction); when every corner
    is taken, lower the bottom of every panel of ``axs`` (their limits stay equal) until the first is free.

    Call last: it measures the figure's final layout (long texts are wrapped first, as
    :func:`app.figures.style.journal` does)."""
    from matplotlib.text import Text
    from matplotlib.transforms import Bbox

    from app.figures.style import wrap_long_texts

    wrap_long_texts(fig)  # the layout as it will be: a title broken in two lines shrinks the panels
    ax = bar.axes
    label = bar.lipspace_label
    pad = 2.0 * fig.dpi / 72.0
    for _ in range(passes):
        fig.draw_without_rendering()
        r = fig.canvas.get_renderer()
        taken = [t.get_window_extent(r) for t in ax.findobj(Text)
                 if t is not label and t.get_visible() and t.get_text().strip() and t.axes is ax
                 and t not in (ax.title, ax.xaxis.label, ax.yaxis.label)]
        taken += _drawn_boxes(ax, exclude=bar)
        taken = [b for b in taken if np.isfinite(b.bounds).all()]
        for corner in BAR_CORNERS:
            _place_bar(ax, bar, corner)
            mine = Bbox.union([label.get_window_extent(r), bar.get_window_extent(r)]).padded(pad)
            if not any(o.overlaps(mine) for o in taken):
                return
        _place_bar(ax, bar, BAR_CORNERS[0])
        mine = Bbox.union([label.get_window_extent(r), bar.get_window_extent(r)])
        hits = [o for o in taken if o.overlaps(mine.padded(pad))]
        # lower the panels' bottom until the bar's top is under the lowest thing it meets
        need_px = mine.y1 - min(o.y0 for o in hits) + pad
        y0, y1 = ax.get_ylim()
        per_px = (y1 - y0) / max(ax.get_window_extent(r).height, 1.0)
        for a in axs:
            a.set_ylim(y0 - 1.2 * need_px * per_px, y1)
        _place_bar(ax, bar, BAR_CORNERS[0])
