"""The manifold view's phone legend: a VTK legend box of coloured circles, added without a render.

pyvista's ``add_legend`` renders the window as it adds the box and rebuilds a circle glyph
for every entry; the phone filter changes the legend on every edit, so each edit paid a
whole extra render of the cloud (~90 ms in software OpenGL at a million frames) and
~5 ms a row. Here the box is built once per legend, every entry shares one circle, and
the render is left to the view's scheduler.
"""
from __future__ import annotations

__all__ = ["add_legend", "remove_legend"]

_FACE = None  # one circle glyph for every entry (pyvista's legend circle)


def _face():
    global _FACE
    if _FACE is None:
        from pyvista.plotting.renderer import make_legend_face

        _FACE = make_legend_face("circle")
    return _FACE


def add_legend(plotter, entries, *, size, loc="lower left", background="white"):
    """Add a legend box of ``entries`` ((label, colour) pairs) to ``plotter``; return the actor.

    Parameters
    ----------
    plotter : pyvista.Plotter
        Any plotter (off-screen in tests); nothing is rendered.
    entries : sequence of (str, colour)
        A colour is anything :class:`pyvista.Color` reads (RGB floats in [0, 1], a name).
    size : (float, float)
        Width and height as fractions of the view.
    loc : str
        A corner as pyvista names it ("lower left", ...).
    """
    import pyvista as pv
    from pyvista.plotting.renderer import map_loc_to_pos
    from vtkmodules.vtkRenderingAnnotation import vtkLegendBoxActor

    actor = vtkLegendBoxActor()
    actor.SetNumberOfEntries(len(entries))
    face = _face()
    for i, (text, colour) in enumerate(entries):
        actor.SetEntry(i, face, str(text), list(pv.Color(colour).float_rgb))
    x, y, (w, h) = map_loc_to_pos(loc, size, border=0.05)
    actor.SetPosition(x, y)
    actor.SetPosition2(w, h)
    actor.SetUseBackground(True)
    actor.SetBackgroundColor(pv.Color(background).float_rgb)
    actor.SetBorder(False)
    actor.GetEntryTextProperty().SetFontFamilyToArial()
    plotter.add_actor(actor, reset_camera=False, pickable=False, name="phone-legend", render=False)
    return actor


def remove_legend(plotter, actor) -> None:
    """Take ``actor`` (from :func:`add_legend`) out of ``plotter`` without a render."""
    plotter.remove_actor(actor, reset_camera=False, render=False)
