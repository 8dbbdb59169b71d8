"""Saving figures: matplotlib figures (PNG/SVG/PDF) and pyvista 3-D views (PNG, SVG/PDF/EPS).

Every writer goes through :func:`engine._atomic.atomic_write`: a failed save removes
its temporary file and leaves any existing file at ``path`` untouched.
"""
from __future__ import annotations

from pathlib import Path

from engine._atomic import atomic_write

__all__ = ["FIGURE_FORMATS", "VECTOR_3D_FORMATS", "VectorExportUnavailable", "save_figure",
           "save_plotter_image", "save_plotter_vector", "vector_export_available"]

#: suffix -> matplotlib format name for 2-D figures
FIGURE_FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}
#: suffixes the VTK gl2ps exporter writes
VECTOR_3D_FORMATS = (".svg", ".pdf", ".eps", ".ps")
#: metadata that would make output differ run to run (dates) is left out
_METADATA = {".png": {"Software": "Lipspace"}, ".svg": {"Date": None, "Creator": "Lipspace"},
             ".pdf": {"CreationDate": None, "ModDate": None, "Creator": "Lipspace"}}


class VectorExportUnavailable(RuntimeError):
    """This VTK build cannot write vector graphics (no gl2ps); PNG still works."""


def _suffix(path, allowed, what):
    suf = Path(path).suffix.lower()
    if suf not in allowed:
        raise ValueError(f"{path}: cannot save {what} as {suf or 'a file without a suffix'!r}; "
                         f"use one of {', '.join(allowed)}")
    return suf


def save_figure(fig, path, *, dpi: float = 200, transparent: bool = False) -> Path:
    """Save a matplotlib figure to ``path`` (.png, .svg or .pdf by suffix), atomically.

    Parameters
    ----------
    fig : matplotlib.figure.Figure
    path : str or Path
        Parent directories are created.
    dpi : float, default=200
        Raster resolution (PNG, and rasterised artists inside SVG/PDF).
    transparent : bool, default=False

    Returns
    -------
    Path
    """
    suf = _suffix(path, FIGURE_FORMATS, "a figure")
    if fig.canvas is None or not hasattr(fig.canvas, "print_figure"):
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        FigureCanvasAgg(fig)
    from matplotlib import rc_context

    # a fixed salt makes SVG element ids (and so the bytes) reproducible
    with rc_context({"svg.hashsalt": "lipspace"}), atomic_write(path) as tmp:
        fig.savefig(tmp, format=FIGURE_FORMATS[suf], dpi=dpi, transparent=transparent,
                    metadata=_METADATA[suf])
    return Path(path)


def save_plotter_image(plotter, path, *, scale: int = 1, transparent: bool = False) -> Path:
    """Save a pyvista plotter's view as PNG via ``plotter.screenshot``, atomically.

    Parameters
    ----------
    plotter : pyvista.Plotter, pyvistaqt.QtInteractor or BackgroundPlotter
        Must be open (not closed) and have rendered or be able to render.
    path : str or Path
        Must end in ``.png``.
    scale : int, default=1
        Resolution multiplier over the window size (2 doubles width and height).
    """
    _suffix(path, (".png",), "a 3-D view image")
    scale = int(scale)
    if scale < 1:
        raise ValueError(f"scale must be a positive integer, got {scale}; 1 keeps the window size")
    return _write_view(plotter, path, lambda tmp: plotter.screenshot(
        str(tmp), transparent_background=transparent, scale=scale, return_img=False), "the renderer produced no image")


def vector_export_available() -> bool:
    """True when this VTK build has the gl2ps exporter (SVG/PDF/EPS of 3-D views)."""
    try:
        from vtkmodules.vtkIOExportGL2PS import vtkGL2PSExporter  # noqa: F401
    except ImportError:
        return False
    return True


def save_plotter_vector(plotter, path, *, title: str = "Lipspace") -> Path:
    """Save a pyvista plotter's view as .svg, .pdf, .eps or .ps, atomically.

    Uses VTK's gl2ps exporter (``plotter.save_graphic``). With VTK's OpenGL2 backend
    (every current VTK wheel) gl2ps writes the 3-D geometry as one embedded raster
    image at window resolution; text, scalar bars and other 2-D overlays are real
    vector primitives. For print quality, enlarge the window or use
    :func:`save_plotter_image` with ``scale=``.

    Raises
    ------
    VectorExportUnavailable
        If this VTK build lacks gl2ps (PNG via :func:`save_plotter_image` still works).
    """
    suf = _suffix(path, VECTOR_3D_FORMATS, "a 3-D view as vector graphics")
    if Path(path).suffix != suf:
        raise ValueError(f"{path}: write the suffix in lower case ({suf}); gl2ps appends its own suffix")
    if not vector_export_available():
        raise VectorExportUnavailable(
            f"{path}: this VTK build has no gl2ps exporter (vtkmodules.vtkIOExportGL2PS), so 3-D views "
            f"cannot be saved as {suf}; save the view as PNG instead (save_plotter_image), or install a "
            "VTK wheel built with gl2ps (the standard PyPI 'vtk' wheels are)")
    # gl2ps writes <prefix><suffix>; the temporary name keeps the suffix, so it writes tmp itself
    return _write_view(plotter, path, lambda tmp: plotter.save_graphic(str(tmp), title=title, raster=True,
                                                                       painter=True), "the gl2ps exporter wrote nothing")


def _write_view(plotter, path, write, empty_message: str) -> Path:
    """Run ``write(tmp)`` for an open plotter through an atomic write; an empty result is an OSError."""
    if getattr(plotter, "render_window", None) is None:
        raise ValueError("this plotter is closed; save the view before closing it")
    with atomic_write(path) as tmp:
        write(tmp)
        if not tmp.exists() or tmp.stat().st_size == 0:
            raise OSError(f"{path}: {empty_message}")
    return Path(path)
