"""The manifold view's colour bar: a VTK scalar bar showing a colour map or whole-hop bands."""
from __future__ import annotations

import numpy as np

__all__ = ["add_scalar_bar", "configure_scalar_bar"]


def add_scalar_bar(plotter):
    """A vertical vtkScalarBarActor at the right of ``plotter``'s view (dark text, title clear of the labels)."""
    import pyvista as pv
    from vtkmodules.vtkRenderingAnnotation import vtkScalarBarActor

    bar = vtkScalarBarActor()
    bar.SetLookupTable(pv.LookupTable(cmap="jet"))
    bar.SetOrientationToVertical()
    bar.SetPosition(0.88, 0.1)
    bar.SetWidth(0.07)
    bar.SetHeight(0.6)
    bar.SetNumberOfLabels(4)
    bar.UnconstrainedFontSizeOn()
    bar.SetVerticalTitleSeparation(14)
    for tp in (bar.GetLabelTextProperty(), bar.GetTitleTextProperty()):
        tp.SetColor(0.1, 0.1, 0.1)
        tp.SetShadow(False)
        tp.SetItalic(False)
        tp.SetFontSize(12)
        tp.SetBold(False)
    plotter.add_actor(bar, reset_camera=False, pickable=False, name="scalar_bar", render=False)
    return bar


def configure_scalar_bar(bar, coloring) -> None:
    """Set a vtkScalarBarActor to show ``coloring``'s scale: a colour map, or a discrete table with
    labels at whole values (hop distance: one band per hop, a label at each whole hop)."""
    if coloring.cmap is None:
        return
    import pyvista as pv
    from vtkmodules.vtkCommonCore import vtkDoubleArray

    lo, hi = coloring.clim
    if isinstance(coloring.cmap, str):
        lut = pv.LookupTable(cmap=coloring.cmap)
        lut.scalar_range = (lo, hi)
    else:
        table = np.asarray(coloring.cmap, dtype=np.float64)
        lut = pv.LookupTable()
        lut.SetNumberOfTableValues(len(table))
        for k, (r, g, b) in enumerate(table):
            lut.SetTableValue(k, r, g, b, 1.0)
        lut.SetRange(lo, hi)
    bar.SetLookupTable(lut)
    bar.SetTitle(coloring.title)
    if coloring.ticks is not None:
        arr = vtkDoubleArray()
        for t in coloring.ticks:
            arr.InsertNextValue(float(t))
        bar.SetUseCustomLabels(True)
        bar.SetCustomLabels(arr)
        bar.SetLabelFormat("%.0f")
        bar.SetMaximumNumberOfColors(len(coloring.cmap))
    else:
        bar.SetUseCustomLabels(False)
        bar.SetLabelFormat("%-#6.3g")
        bar.SetMaximumNumberOfColors(256)
