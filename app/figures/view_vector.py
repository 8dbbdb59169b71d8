"""A 3-D view as a vector figure: the scene's own geometry projected through its camera.

VTK's gl2ps exporter, with the OpenGL2 backend of every current VTK wheel, writes the
3-D geometry of a view as one embedded raster image (only text stays vector). This
module instead reads what each visible actor draws (points, lines, triangles, their
colours, opacity and placement), projects it with the view's camera exactly as on
screen, and draws it with matplotlib as vector primitives: points as markers, lines as
polylines, surfaces as shaded polygons sorted back to front (painter's
algorithm; back faces culled where the actor culls them); opaque smooth-shaded
surfaces (the lips) as Gouraud triangles shaded from their vertex normals, as on screen. The colour bar, the legend,
3-D text labels and plain text overlays are redrawn as matplotlib text and patches.
Layered renderers (the manifold view's overlay) are drawn after the main one, as on
screen.

The result is a :class:`matplotlib.figure.Figure` the width of a journal column (or any
width: as on screen, the view's pixels at :data:`SCREEN_DPI`), the view's proportions kept,
its text at the journal's sizes (:func:`app.figures.style.journal_rc`, never below 6 pt):
PNG, SVG and PDF are all written from it (:mod:`app.figures.view_export`), so they carry
the same labels as the screen. Translucent flat surfaces (the zero-velocity plane) are one
filled outline, not polygons side by side, whose overlapping edges would print as a grid.
"""
from __future__ import annotations

import numpy as np

from app.figures.style import SCREEN_DPI, font_pt
from app.scene.projection import project, view_transform

__all__ = ["scene_figure"]



def _matrix(actor) -> np.ndarray:
    m = actor.GetMatrix()
    return np.array([[m.GetElement(r, c) for c in range(4)] for r in range(4)], dtype=np.float64)


def _colours(actor, mesh, n_points):
    """Per-point RGBA in [0, 1] (n, 4) when the actor colours by scalars, else None."""
    mapper = actor.GetMapper()
    if not mapper.GetScalarVisibility() or n_points == 0:
        return None
    from vtkmodules.util.numpy_support import vtk_to_numpy

    arr = mapper.MapScalars(mesh, 1.0)
    if arr is None or arr.GetNumberOfTuples() != n_points:
        return None
    c = vtk_to_numpy(arr).astype(np.float64) / 255.0
    if c.ndim == 1 or c.shape[1] < 3:
        return None
    if c.shape[1] == 3:
        c = np.column_stack([c, np.ones(len(c))])
    return c


def _cells(poly, kind):
    """Connectivity of a vtkCellArray (verts, lines or polys) as a list of index arrays."""
    from vtkmodules.util.numpy_support import vtk_to_numpy

    ca = {"verts": poly.GetVerts, "lines": poly.GetLines, "polys": poly.GetPolys}[kind]()
    if ca is None or ca.GetNumberOfCells() == 0:
        return []
    offsets = vtk_to_numpy(ca.GetOffsetsArray()).astype(np.int64)
    conn = vtk_to_numpy(ca.GetConnectivityArray()).astype(np.int64)
    return [conn[a:b] for a, b in zip(offsets[:-1], offsets[1:])]


def _actor_primitives(actor, M, size, view_dir):
    """The actor's drawn primitives in display coordinates: list of (kind, depth, data...)."""
    import pyvista as pv

    mapper = actor.GetMapper()
    if mapper is None:
        return [], 0.0
    data = mapper.GetInputAsDataSet() if hasattr(mapper, "GetInputAsDataSet") else mapper.GetInput()
    if data is None or data.GetNumberOfPoints() == 0:
        return [], 0.0
    mesh = pv.wrap(data)
    if not isinstance(mesh, pv.PolyData):
        mesh = mesh.extract_surface(algorithm=None)
    prop = actor.GetProperty()
    A = _matrix(actor)
    P = np.asarray(mesh.points, dtype=np.float64)
    W = P @ A[:3, :3].T + A[:3, 3]
    xy, depth = project(W, M, size)
    n = len(P)
    per_point = _colours(actor, mesh, n)
    base = np.array([*prop.GetColor(), prop.GetOpacity()], dtype=np.float64)
    col = per_point if per_point is not None else np.broadcast_to(base, (n, 4))
    col = col.copy()
    col[:, 3] *= prop.GetOpacity() if per_point is not None else 1.0
    rep = prop.GetRepresentation()  # 0 points, 1 wireframe, 2 surface
    out = []
    verts = _cells(mesh, "verts")
    lines = _cells(mesh, "lines")
    polys = _cells(mesh, "polys") if hasattr(mesh, "GetPolys") else []
    if mesh.n_cells == 0:
        verts = [np.arange(n)]
    if rep == 0:
        verts = [np.arange(n)]
        lines, polys = [], []
    if verts:
        idx = np.unique(np.concatenate(verts))
        out.append(("points", xy[idx], depth[idx], col[idx], float(prop.GetPointSize())))
    for ids in lines:
        out.append(("line", xy[ids], depth[ids], col[ids].mean(0), float(prop.GetLineWidth())))
    if polys:
        tri = [ids for ids in polys if len(ids) >= 3]
        if tri:
            cull = bool(prop.GetBackfaceCulling())
            # smooth-shaded opaque surfaces (the lips) are drawn as Gouraud triangles: flat facets
            # showed where the window shows a smooth surface; see-through ones stay flat polygons
            smooth = prop.GetInterpolation() != 0 and base[3] >= 1.0 and (per_point is None or col[:, 3].min() >= 1.0)
            # edges as the screen shows them: on opaque surfaces (a see-through one shows none)
            edges = bool(prop.GetEdgeVisibility()) and base[3] >= 1.0
            edge_col = np.array([*prop.GetEdgeColor(), base[3]])
            tri3 = [ids for ids in tri if len(ids) == 3]
            other = [ids for ids in tri if len(ids) != 3]
            faces, fdepth, fcol = [], [], []
            groups = ([np.asarray(tri3)] if tri3 else []) + [ids[None, :] for ids in other]
            for T in groups:  # (n_faces, k) vertex ids, all triangles at once
                p2 = xy[T]
                # signed area on screen: negative = facing away (VTK's counter-clockwise front faces)
                area = 0.5 * np.sum(p2[..., 0] * np.roll(p2[..., 1], -1, axis=1)
                                    - np.roll(p2[..., 0], -1, axis=1) * p2[..., 1], axis=1)
                keep = area > 0 if cull else np.ones(len(T), bool)
                T, p2 = T[keep], p2[keep]
                if len(T) == 0:
                    continue
                if smooth and T.shape[1] == 3:
                    # as on screen: the shade interpolated over each triangle from its corners' normals
                    # (the window's own normals: VTK's filter, unweighted, as app.scene.lips.point_normals)
                    from app.scene.lips import point_normals

                    vshade = 0.45 + 0.55 * np.abs(point_normals(W, np.asarray(tri3)) @ view_dir)
                    vc = col[T].copy()
                    vc[..., :3] = np.clip(vc[..., :3] * vshade[T][..., None], 0, 1)
                    out.append(("gouraud", p2, depth[T].mean(axis=1), vc))
                    continue
                # flat: each face shaded by its own normal
                w3 = W[T[:, :3]]
                nrm = np.cross(w3[:, 1] - w3[:, 0], w3[:, 2] - w3[:, 0])
                nn = np.linalg.norm(nrm, axis=1)
                cosv = np.where(nn > 0, np.abs(nrm @ view_dir) / np.where(nn > 0, nn, 1.0), 1.0)
                shade = 0.45 + 0.55 * cosv
                c = col[T].mean(axis=1)
                faces.extend(list(p2))
                fdepth.extend(depth[T].mean(axis=1))
                fcol.extend(np.column_stack([np.clip(c[:, :3] * shade[:, None], 0, 1), c[:, 3]]))
            if faces:
                out.append(("polys", faces, np.asarray(fdepth), np.asarray(fcol), edge_col if edges else None))
    return out, (float(depth.max()) if n else 0.0, float(depth.mean()) if n else 0.0)


def _gouraud_artist(verts, colours, zorder):
    """An artist drawing triangles (m, 3, 2) with corner colours (m, 3, 4) interpolated over each.

    The PDF/EPS backends write one Gouraud shading; SVG approximates it with gradients.
    """
    from matplotlib.artist import Artist

    class GouraudTriangles(Artist):
        def draw(self, renderer):
            if not self.get_visible():
                return
            gc = renderer.new_gc()
            renderer.draw_gouraud_triangles(gc, verts, colours, self.axes.transData.frozen())
            gc.restore()

    a = GouraudTriangles()
    a.set_zorder(zorder)
    return a


def _draw(ax, prims, zbase, pt):
    """Draw ``prims`` on ``ax`` from z-order ``zbase``; ``pt``: points per screen pixel (markers, lines)."""
    from matplotlib.collections import LineCollection, PolyCollection

    z = zbase
    for prim in prims:
        kind = prim[0]
        if kind == "points":
            _, xy, depth, col, size = prim
            order = np.argsort(-depth)  # far first
            s = (max(size, 1.0) * pt) ** 2
            ax.scatter(xy[order, 0], xy[order, 1], s=s, c=col[order], marker="o", linewidths=0, zorder=z)
        elif kind == "line":
            _, xy, depth, col, width = prim
            ax.add_collection(LineCollection([xy], colors=[col], linewidths=max(width, 0.5) * pt,
                                             capstyle="round", joinstyle="round", zorder=z))
        elif kind == "gouraud":
            _, tris, depth, vcol = prim
            order = np.argsort(-depth)  # far first
            ax.add_artist(_gouraud_artist(tris[order], vcol[order], z))
        else:
            _, faces, depth, fcol, edge = prim
            order = np.argsort(-depth)
            if edge is None and len(faces) > 1 and fcol[:, 3].max() < 1.0 and np.ptp(fcol, axis=0).max() < 1e-3:
                # one see-through colour (the zero-velocity plane): one outline filled once; polygons side by
                # side would overlap their edges and print as a grid that is not on screen
                from matplotlib.patches import PathPatch
                from matplotlib.path import Path

                path = Path.make_compound_path(*[Path(np.vstack([f, f[:1]]), closed=True) for f in faces])
                ax.add_patch(PathPatch(path, facecolor=fcol[0], edgecolor="none", lw=0, zorder=z))
                z += 1
                continue
            pc = PolyCollection([faces[k] for k in order], facecolors=fcol[order], zorder=z,
                                edgecolors=[edge] if edge is not None else fcol[order],
                                linewidths=0.4 * pt if edge is not None else 0.25 * pt)
            ax.add_collection(pc)
        z += 1
    return z


def _scalar_bar(fig, bar, size):
    """Redraw a vtkScalarBarActor as a matplotlib colour bar at the same place."""
    from matplotlib.colorbar import ColorbarBase
    from matplotlib.colors import BoundaryNorm, ListedColormap, Normalize

    lut = bar.GetLookupTable()
    lo, hi = lut.GetRange()
    n = lut.GetNumberOfTableValues() if hasattr(lut, "GetNumberOfTableValues") else 256
    table = np.array([lut.GetTableValue(k)[:3] for k in range(n)]) if n > 0 else np.zeros((1, 3))
    cmap = ListedColormap(table)
    x, y = bar.GetPosition()
    w, h = bar.GetWidth(), bar.GetHeight()
    cax = fig.add_axes([x + 0.25 * w, y, 0.3 * w, h * 0.9])
    if bar.GetUseCustomLabels():
        labels = bar.GetCustomLabels()
        ticks = [labels.GetValue(k) for k in range(labels.GetNumberOfTuples())]
        norm = BoundaryNorm(np.linspace(lo, hi, n + 1), n)
        texts = [f"{t:.0f}" for t in ticks]
    else:  # the labels the screen shows: evenly spaced from the lowest to the highest, in the bar's format
        ticks = list(np.linspace(lo, hi, max(bar.GetNumberOfLabels(), 2)))
        norm = Normalize(lo, hi)
        texts = [_printf(bar.GetLabelFormat() or "%-#6.3g", t) for t in ticks]
    cb = ColorbarBase(cax, cmap=cmap, norm=norm, ticks=ticks, orientation="vertical")
    if cb.solids is not None:
        cb.solids.set_rasterized(False)  # matplotlib rasterises bars of 50+ colours: keep them vector
    cb.set_ticklabels(texts)
    cb.ax.tick_params(labelsize=font_pt(-1), width=0.5, length=2)
    # right-aligned over the bar: the bar sits at the view's right edge, a title running right would be cut
    cax.set_title(bar.GetTitle() or "", fontsize=font_pt(-1), pad=4, loc="right")
    return cax


def _inside(fig, cax) -> None:
    """Move the colour bar's axes ``cax`` (with its labels and title) back inside the figure where they stick out."""
    fig.draw_without_rendering()
    r = fig.canvas.get_renderer()
    bb = cax.get_tightbbox(r)
    page = fig.bbox
    dx = min(0.0, page.x1 - 2.0 - bb.x1) + max(0.0, page.x0 + 2.0 - bb.x0)
    dy = min(0.0, page.y1 - 2.0 - bb.y1) + max(0.0, page.y0 + 2.0 - bb.y0)
    if dx or dy:
        pos = cax.get_position()
        cax.set_position([pos.x0 + dx / page.width, pos.y0 + dy / page.height, pos.width, pos.height])


def _printf(fmt: str, value: float) -> str:
    """``value`` in a C printf format as VTK writes its labels (``"%-#6.3g"``), without padding."""
    try:
        return (fmt % value).strip()
    except (TypeError, ValueError):
        return f"{value:.3g}"


#: a legend box's symbol (app.scene.legend.SYMBOLS) as a matplotlib legend handle's style
_HANDLE_STYLE = {"circle": {"ls": "none", "marker": "o"}, "square": {"ls": "none", "marker": "s"},
                 "line": {"ls": "-", "marker": ">", "markevery": [1]}, "arrow": {"ls": "-", "marker": ">", "lw": 0.6,
                                                                             "markevery": [1]},
                 "ring": {"ls": "none", "marker": "o", "mfc": "none"}}


def _entry(legend, k):
    """Entry ``k`` of a vtkLegendBoxActor: (text, symbol colour, symbol name). The colour is the symbol's own
    (its ``rgb`` point scalars, :mod:`app.scene.legend`), else the entry's colour; the name is the symbol's tag."""
    symbol = legend.GetEntrySymbol(k)
    colour, kind = legend.GetEntryColor(k), "circle"
    if symbol is not None:
        pd = symbol.GetPointData().GetArray("rgb")
        if pd is not None and pd.GetNumberOfTuples():
            colour = tuple(c / 255.0 for c in pd.GetTuple(0)[:3])
        tag = symbol.GetFieldData().GetAbstractArray("symbol")
        if tag is not None and tag.GetNumberOfValues():
            kind = str(tag.GetValue(0))
    return legend.GetEntryString(k), tuple(colour), kind


def _handles(legend) -> list:
    """A vtkLegendBoxActor's entries as matplotlib legend handles: each symbol (a marker, a line or an arrow)
    in its colour."""
    from matplotlib.lines import Line2D

    out = []
    for k in range(legend.GetNumberOfEntries()):
        text, colour, kind = _entry(legend, k)
        style = dict(_HANDLE_STYLE.get(kind, _HANDLE_STYLE["circle"]))
        out.append(Line2D([0, 1], [0, 0], color=colour, ms=4, label=text, **style))
    return out


def _legend(ax, legend):
    """A vtkLegendBoxActor as a matplotlib legend in the same corner of the view, on the same translucent
    white box (the view as on screen)."""
    from matplotlib.legend import Legend

    handles = _handles(legend)
    if not handles:
        return None
    x, y = legend.GetPosition()
    w, h = legend.GetPosition2()
    top, right = y + h / 2 > 0.5, x + w / 2 > 0.5
    loc = f"{'upper' if top else 'lower'} {'right' if right else 'left'}"
    anchor = (x + w if right else x, y + h if top else y)
    leg = Legend(ax, handles, [hd.get_label() for hd in handles], loc=loc, bbox_to_anchor=anchor,
                 bbox_transform=ax.transAxes, fontsize=font_pt(-1), frameon=True, framealpha=0.85,
                 borderaxespad=0.0, handlelength=1.6, labelspacing=0.3, borderpad=0.3)
    leg.get_frame().set_edgecolor("none")
    leg.set_zorder(1000)
    ax.add_artist(leg)  # one artist per legend box: a second box must not replace the first
    return leg


def _legend_below(fig, boxes) -> None:
    """Every legend box's entries in one legend below the view (a journal width: the screen's corner boxes,
    at print text sizes, would cover a third of the view): the figure grows by the legend's height and
    every axes keeps its size in inches."""
    handles = [hd for b in boxes for hd in _handles(b)]
    if not handles:
        return
    from app.figures.style import one_column

    W, H0 = fig.get_size_inches()
    leg = fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, 0.0), ncol=2 if one_column(W) else 3,
                     fontsize=font_pt(-1), frameon=False, handlelength=1.6, labelspacing=0.3, columnspacing=1.2,
                     borderaxespad=0.0)
    leg.set_gid("view:legend")
    fig.draw_without_rendering()
    strip = leg.get_window_extent(fig.canvas.get_renderer()).height / fig.dpi + 0.06  # inches
    H = H0 + strip
    for a in fig.axes:
        p = a.get_position()
        a.set_position([p.x0, (p.y0 * H0 + strip) / H, p.width, p.height * H0 / H])
    fig.set_size_inches(W, H)
    leg.set_bbox_to_anchor((0.5, (strip - 0.03) / H), transform=fig.transFigure)


def _labels_2d(ax, actor, M, size, z):
    """3-D point labels (vtkLabelPlacementMapper) and text actors, as matplotlib text."""
    import pyvista as pv

    mapper = actor.GetMapper()
    cls = type(mapper).__name__ if mapper is not None else ""
    if cls == "vtkLabelPlacementMapper":
        alg = mapper.GetInputAlgorithm()
        src = pv.wrap(alg.GetInputDataObject(0, 0))
        name = alg.GetLabelArrayName() or "labels"
        if src is None or name not in src.point_data:
            return
        xy, _ = project(np.asarray(src.points, dtype=np.float64), M, size)
        prop = alg.GetTextProperty() if hasattr(alg, "GetTextProperty") else None
        colour = prop.GetColor() if prop is not None else (0, 0, 0)
        # justified as on screen: a label's text runs away from what it names
        ha = {"Left": "left", "Right": "right"}.get(prop.GetJustificationAsString() if prop else "", "center")
        va = {"Bottom": "bottom", "Top": "top"}.get(prop.GetVerticalJustificationAsString() if prop else "", "center")
        for (x, y), text in zip(xy, src.point_data[name]):
            ax.text(x, y, str(text), fontsize=font_pt(), ha=ha, va=va, zorder=z, color=colour)
    elif hasattr(actor, "GetInput") and hasattr(actor, "GetTextProperty"):  # vtkTextActor
        text = actor.GetInput()
        if text:
            pos = actor.GetPosition()
            ax.text(pos[0], pos[1], text, fontsize=font_pt(-1), ha="left", va="bottom", zorder=z,
                    color=actor.GetTextProperty().GetColor())


def scene_figure(plotter, *, title: str | None = None, width: float | None = None):
    """A matplotlib Figure drawing ``plotter``'s current view as vector primitives.

    Parameters
    ----------
    plotter : pyvista plotter (open; its camera as shown)
    title : str, optional
        Drawn at the top, above everything else.
    width : float, optional
        Width in inches (85 mm: one journal column); the view keeps its proportions and the
        view's legend boxes go into one legend below it (the figure grows by its height).
        Default: as on screen (the view's pixels at :data:`SCREEN_DPI`, each legend box in its
        corner).

    Returns
    -------
    matplotlib.figure.Figure
        Its ``lipspace`` dict holds ``n_points`` (markers drawn), ``n_polygons``, ``n_lines``,
        ``texts`` (every label drawn: the view's own, as on screen) and ``width_mm``.
    """
    from matplotlib import rc_context

    from app.figures.style import journal_rc

    M, size = view_transform(plotter)
    w, h = size
    if w < 2 or h < 2:
        raise ValueError(f"the 3-D view is {w}x{h} pixels on screen; show it (open its dock) before exporting it")
    journal_width = width is not None
    width = w / SCREEN_DPI if width is None else float(width)
    with rc_context(journal_rc(width)):
        return _scene_figure(plotter, M, size, title, width, below=journal_width)


def _scene_figure(plotter, M, size, title, width, *, below=False):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    main = plotter.renderer
    w, h = size
    fig = Figure(figsize=(width, width * h / w), dpi=100)
    FigureCanvasAgg(fig)
    pt = width * 72.0 / w  # points per screen pixel
    bg = main.GetBackground()
    fig.patch.set_facecolor(bg)
    ax = fig.add_axes([0, 0, 1, 1])
    ax.set_xlim(0, w)
    ax.set_ylim(0, h)
    ax.set_axis_off()
    cam = main.GetActiveCamera()
    view_dir = np.subtract(cam.GetFocalPoint(), cam.GetPosition())
    view_dir = view_dir / max(np.linalg.norm(view_dir), 1e-300)
    renderers = [main]
    overlay = getattr(plotter, "_lipspace_overlay", None)
    if overlay is not None:
        renderers.append(overlay)
    counts = {"n_points": 0, "n_polygons": 0, "n_lines": 0}
    z = 1
    for ren in renderers:
        layer = []
        actors = ren.GetActors()
        actors.InitTraversal()
        for _ in range(actors.GetNumberOfItems()):
            a = actors.GetNextActor()
            if not a.GetVisibility():
                continue
            prims, far = _actor_primitives(a, M, size, view_dir)
            if prims:
                layer.append((far, prims))
        # painter's algorithm over actors: in the main layer the actor reaching farthest goes first (the
        # plane behind the cloud, markers inside it after it); in the overlay, by mean depth
        k = 0 if ren is main else 1
        for _far, prims in sorted(layer, key=lambda t: -t[0][k]):
            for p in prims:
                if p[0] == "points":
                    counts["n_points"] += len(p[1])
                elif p[0] == "line":
                    counts["n_lines"] += 1
                else:
                    counts["n_polygons"] += len(p[1])
            z = _draw(ax, prims, z, pt)
    bars, boxes = [], []
    for ren in renderers:
        props = ren.GetViewProps()
        props.InitTraversal()
        for _ in range(props.GetNumberOfItems()):
            a = props.GetNextProp()
            if not a.IsA("vtkActor2D") or not a.GetVisibility():
                continue
            cls = type(a).__name__
            if cls == "vtkScalarBarActor":
                bars.append(_scalar_bar(fig, a, size))
            elif cls == "vtkLegendBoxActor":
                boxes.append(a)
            else:
                _labels_2d(ax, a, M, size, z + 1)
    if below:
        _legend_below(fig, boxes)
    else:
        for b in boxes:
            _legend(ax, b)
    if title:
        fig.suptitle(title, fontsize=font_pt(1), y=0.985, va="top")
    for cax in bars:  # at a journal width the bar's labels are larger against the view: keep them on the page
        _inside(fig, cax)
    from matplotlib.text import Text

    counts["texts"] = [t.get_text() for t in fig.findobj(Text) if t.get_visible() and t.get_text().strip()]
    counts["width_mm"] = width * 25.4
    fig.lipspace = counts
    return fig
