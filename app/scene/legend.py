"""The manifold view's legends: VTK legend boxes of symbols and names, added without a render.

pyvista's ``add_legend`` renders the window as it adds the box and rebuilds a glyph for every
entry; the phone filter changes the legend on every edit, so each edit paid a whole extra
render of the cloud (~90 ms in software OpenGL at a million frames) and ~5 ms a row. Here
the box is built once per legend, every entry of a symbol shares one glyph, and the render
is left to the view's scheduler. An entry's symbol says what kind of thing it names: a
``circle`` (points, markers), a ``line`` (a trajectory or path, with its arrowhead), an
``arrow`` (a direction: S, V, the local frame), a ``ring`` (a cluster ellipsoid's outline).
"""
from __future__ import annotations

import numpy as np

__all__ = ["add_legend", "set_entries", "remove_legend", "SYMBOLS"]

SYMBOLS = ("circle", "line", "arrow", "ring", "square")
#: the names' colour: dark, so a pale category colour (yellow) stays readable; the symbol carries the colour
TEXT_RGB = (0.1, 0.1, 0.1)
_FACES: dict = {}  # one glyph per symbol
_COLOURED: dict = {}  # one coloured copy per (symbol, colour)


def _coloured(symbol: str, rgb):
    """The ``symbol``'s glyph with every point in ``rgb`` (0-255), made once per colour."""
    import numpy as np

    key = (symbol, tuple(int(c) for c in rgb))
    if key not in _COLOURED:
        face = _face(symbol).copy()
        face.point_data["rgb"] = np.tile(np.asarray(key[1], np.uint8), (face.n_points, 1))
        face.point_data.active_scalars_name = "rgb"
        _COLOURED[key] = face
    return _COLOURED[key]


def _face(symbol: str):
    if symbol not in SYMBOLS:
        raise ValueError(f"legend symbol must be one of {SYMBOLS}, got {symbol!r}")
    if symbol not in _FACES:
        import pyvista as pv
        from pyvista.plotting.renderer import make_legend_face

        if symbol in ("circle", "square"):
            face = make_legend_face("circle" if symbol == "circle" else "rectangle")
        elif symbol == "line":  # a bar with an arrowhead: a path that runs left to right
            pts = np.array([[-1, -0.18, 0], [0.35, -0.18, 0], [0.35, -0.5, 0], [1, 0, 0], [0.35, 0.5, 0],
                            [0.35, 0.18, 0], [-1, 0.18, 0]], float)
            face = pv.PolyData(pts, faces=[7, 0, 1, 2, 3, 4, 5, 6]).triangulate()
        elif symbol == "arrow":  # a thin shaft and a wide head
            pts = np.array([[-1, -0.08, 0], [0.3, -0.08, 0], [0.3, -0.35, 0], [1, 0, 0], [0.3, 0.35, 0],
                            [0.3, 0.08, 0], [-1, 0.08, 0]], float)
            face = pv.PolyData(pts, faces=[7, 0, 1, 2, 3, 4, 5, 6]).triangulate()
        else:  # ring: an ellipse's outline
            a = np.linspace(0, 2 * np.pi, 33)[:-1]
            outer = np.c_[np.cos(a), 0.7 * np.sin(a), np.zeros_like(a)]
            inner = 0.7 * outer
            pts = np.vstack([outer, inner])
            n = len(a)
            quads = [[4, i, (i + 1) % n, n + (i + 1) % n, n + i] for i in range(n)]
            face = pv.PolyData(pts, faces=np.ravel(quads)).triangulate()
        _FACES[symbol] = face
    return _FACES[symbol]


def add_legend(plotter, entries, *, size, loc="lower left", background="white", name: str = "phone-legend"):
    """Add a legend box of ``entries`` to ``plotter``; return the actor.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Any plotter (off-screen in tests); nothing is rendered.
    entries : sequence of (str, colour) or (str, colour, symbol)
        A colour is anything :class:`pyvista.Color` reads (RGB floats in [0, 1], a name); a
        symbol one of :data:`SYMBOLS` (default ``"circle"``).
    size : (float, float)
        Width and height as fractions of the view.
    loc : str
        A corner as pyvista names it ("lower left", ...).
    name : str
        The actor's name in the plotter (one legend per name).
    """
    import pyvista as pv
    from vtkmodules.vtkRenderingAnnotation import vtkLegendBoxActor

    actor = vtkLegendBoxActor()
    set_entries(actor, entries, size=size, loc=loc)
    actor.SetUseBackground(True)
    actor.SetBackgroundColor(pv.Color(background).float_rgb)
    actor.SetBackgroundOpacity(0.85)
    actor.SetBorder(False)
    actor.GetEntryTextProperty().SetFontFamilyToArial()
    plotter.add_actor(actor, reset_camera=False, pickable=False, name=name, render=False)
    return actor


def set_entries(actor, entries, *, size, loc="lower left") -> None:
    """Give a legend box from :func:`add_legend` new ``entries``, size and corner, in place (no actor is
    added or removed: a click changes the legend without touching the scene's actors). No entries: hidden."""
    import pyvista as pv
    from pyvista.plotting.renderer import map_loc_to_pos

    actor.SetNumberOfEntries(len(entries))
    actor.ScalarVisibilityOn()  # each symbol in its colour (its scalars), each name in dark text (readable on white)
    for i, entry in enumerate(entries):
        text, colour = entry[0], entry[1]
        symbol = entry[2] if len(entry) > 2 else "circle"
        actor.SetEntry(i, _coloured(symbol, pv.Color(colour).int_rgb), str(text), list(TEXT_RGB))
    x, y, (w, h) = map_loc_to_pos(loc, size, border=0.05)
    actor.SetPosition(x, y)
    actor.SetPosition2(w, h)
    actor.SetVisibility(len(entries) > 0)


def remove_legend(plotter, actor) -> None:
    """Take ``actor`` (from :func:`add_legend`) out of ``plotter`` without a render."""
    plotter.remove_actor(actor, reset_camera=False, render=False)
