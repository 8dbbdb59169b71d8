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

The result is a :class:`matplotlib.figure.Figure` the size of the view (at 100 dpi),
saved by :func:`app.figures.export.save_plotter_vector` as SVG or PDF.
"""
from __future__ import annotations

import numpy as np

from app.scene.projection import project, view_transform

__all__ = ["scene_figure"]

DPI = 100.0


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
            edges = bool(prop.GetEdgeVisibility())
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


def _draw(ax, prims, zbase):
    from matplotlib.collections import LineCollection, PolyCollection

    z = zbase
    for prim in prims:
        kind = prim[0]
        if kind == "points":
            _, xy, depth, col, size = prim
            order = np.argsort(-depth)  # far first
            s = (max(size, 1.0) * 72.0 / DPI) ** 2
            ax.scatter(xy[order, 0], xy[order, 1], s=s, c=col[order], marker="o", linewidths=0, zorder=z)
        elif kind == "line":
            _, xy, depth, col, width = prim
            ax.add_collection(LineCollection([xy], colors=[col], linewidths=max(width, 0.5) * 72.0 / DPI,
                                             capstyle="round", joinstyle="round", zorder=z))
        elif kind == "gouraud":
            _, tris, depth, vcol = prim
            order = np.argsort(-depth)  # far first
            ax.add_artist(_gouraud_artist(tris[order], vcol[order], z))
        else:
            _, faces, depth, fcol, edge = prim
            order = np.argsort(-depth)
            pc = PolyCollection([faces[k] for k in order], facecolors=fcol[order], zorder=z,
                                edgecolors=[edge] if edge is not None else fcol[order],
                                linewidths=0.4 if edge is not None else 0.25)
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
    else:
        ticks = None
        norm = Normalize(lo, hi)
    cb = ColorbarBase(cax, cmap=cmap, norm=norm, ticks=ticks, orientation="vertical")
    if cb.solids is not None:
        cb.solids.set_rasterized(False)  # matplotlib rasterises bars of 50+ colours: keep them vector
    if ticks is not None:
        cb.set_ticklabels([f"{t:.0f}" for t in ticks])
    cb.ax.tick_params(labelsize=8)
    # right-aligned over the bar: the bar sits at the view's right edge, a title running right would be cut
    cax.set_title(bar.GetTitle() or "", fontsize=9, pad=8, loc="right")
    return cax


def _legend(ax, legend):
    from matplotlib.lines import Line2D

    handles = []
    for k in range(legend.GetNumberOfEntries()):
        handles.append(Line2D([], [], ls="none", marker="o", ms=6, color=legend.GetEntryColor(k),
                              label=legend.GetEntryString(k)))
    if handles:
        ax.legend(handles=handles, loc="lower left", fontsize=8, frameon=False)


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
        for (x, y), text in zip(xy, src.point_data[name]):
            ax.text(x, y, str(text), fontsize=11, ha="center", va="center", zorder=z)
    elif hasattr(actor, "GetInput") and hasattr(actor, "GetTextProperty"):  # vtkTextActor
        text = actor.GetInput()
        if text:
            pos = actor.GetPosition()
            ax.text(pos[0], pos[1], text, fontsize=actor.GetTextProperty().GetFontSize() * 0.75,
                    ha="left", va="bottom", zorder=z, color=actor.GetTextProperty().GetColor())


def scene_figure(plotter, *, title: str | None = None):
    """A matplotlib Figure drawing ``plotter``'s current view as vector primitives.

    Parameters
    ----------
    plotter : pyvista plotter (open; its camera as shown)
    title : str, optional
        Drawn at the top, above everything else.

    Returns
    -------
    matplotlib.figure.Figure
        Sized as the view (``window pixels / 100`` inches); its ``lipspace`` dict holds
        ``n_points`` (markers drawn), ``n_polygons`` and ``n_lines``.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    main = plotter.renderer
    M, size = view_transform(plotter)
    w, h = size
    if w < 2 or h < 2:
        raise ValueError(f"the 3-D view is {w}x{h} pixels on screen; show it (open its dock) before exporting it")
    fig = Figure(figsize=(w / DPI, h / DPI), dpi=DPI)
    FigureCanvasAgg(fig)
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
            z = _draw(ax, prims, z)
    for ren in renderers:
        props = ren.GetViewProps()
        props.InitTraversal()
        for _ in range(props.GetNumberOfItems()):
            a = props.GetNextProp()
            if not a.IsA("vtkActor2D") or not a.GetVisibility():
                continue
            cls = type(a).__name__
            if cls == "vtkScalarBarActor":
                _scalar_bar(fig, a, size)
            elif cls == "vtkLegendBoxActor":
                _legend(ax, a)
            else:
                _labels_2d(ax, a, M, size, z + 1)
    if title:
        fig.suptitle(title, fontsize=11, y=0.985, va="top")
    fig.lipspace = counts
    return fig
