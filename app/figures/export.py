"""Saving figures: matplotlib figures (PNG/SVG/PDF) and pyvista 3-D views (PNG, SVG/PDF/EPS).

Every writer goes through :func:`engine.files.atomic.atomic_write`: a failed save removes
its temporary file and leaves any existing file at ``path`` untouched.
"""
from __future__ import annotations

from pathlib import Path

from app.figures.style import SCREEN_DPI
from engine.files.atomic import atomic_write

__all__ = ["FIGURE_FORMATS", "VECTOR_3D_FORMATS", "VectorExportUnavailable", "save_figure", "suffix_from_filter",
           "filter_suffixes", "save_vector_figure", "save_plotter_image", "save_plotter_vector",
           "vector_export_available"]

#: suffix -> matplotlib format name for 2-D figures
FIGURE_FORMATS = {".png": "png", ".svg": "svg", ".pdf": "pdf"}
#: suffixes 3-D views are saved to as vector graphics
VECTOR_3D_FORMATS = (".svg", ".pdf", ".eps")
#: text in vector files: PDF/PS embed the TrueType font (Type 42: text stays text, selectable and editable, the
#: font travels with the file); SVG draws glyph outlines ("path": an SVG cannot carry a font file, and outlines
#: look the same on every machine and in every journal's pipeline)
EMBEDDED_FONTS = {"pdf.fonttype": 42, "ps.fonttype": 42, "svg.fonttype": "path"}
#: metadata that would make output differ run to run (dates) is left out
_METADATA = {".png": {"Software": "Lipspace"}, ".svg": {"Date": None, "Creator": "Lipspace"},
             ".pdf": {"CreationDate": None, "ModDate": None, "Creator": "Lipspace"}}


class VectorExportUnavailable(RuntimeError):
    """Never raised: vector export does not depend on the VTK build; callers may still catch it."""


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

    # a fixed salt makes SVG element ids (and so the bytes) reproducible; fonts go with the file (EMBEDDED_FONTS)
    with rc_context({"svg.hashsalt": "lipspace", **EMBEDDED_FONTS}), atomic_write(path) as tmp:
        fig.savefig(tmp, format=FIGURE_FORMATS[suf], dpi=dpi, transparent=transparent,
                    metadata=_METADATA[suf])
    return Path(path)




def save_plotter_image(plotter, path, *, scale: int = 1, dpi: float | None = None,
                       transparent: bool = False) -> Path:
    """Save a pyvista plotter's view as PNG via ``plotter.screenshot``, atomically.

    Parameters
    ----------
    plotter : pyvista.Plotter, pyvistaqt.QtInteractor or BackgroundPlotter
        Must be open (not closed) and have rendered or be able to render.
    path : str or Path
        Must end in ``.png`` (any case).
    scale : int, default=1
        Resolution multiplier over the window size (2 doubles width and height).
    dpi : float, optional
        Print resolution instead of ``scale``: the view keeps its on-screen size (window
        pixels at :data:`SCREEN_DPI`) and gets ``dpi`` pixels per inch: it is rendered at
        the next whole multiple of the window size and resampled to
        ``round(window * dpi / 96)`` pixels; the PNG records the DPI.
    """
    _suffix(path, (".png",), "a 3-D view image")
    scale = int(scale)
    if scale < 1:
        raise ValueError(f"scale must be a positive integer, got {scale}; 1 keeps the window size")
    if dpi is None:
        return _write_view(plotter, path, lambda tmp: plotter.screenshot(
            str(tmp), transparent_background=transparent, scale=scale, return_img=False),
            "the renderer produced no image")
    dpi = float(dpi)
    if not (30.0 <= dpi <= 1200.0):
        raise ValueError(f"dpi {dpi:g} is outside 30..1200; 96 keeps the window's pixels, 300 is print quality")

    def write(tmp):
        import math

        from PIL import Image

        w, h = (int(v) for v in plotter.window_size)
        k = max(1, math.ceil(dpi / SCREEN_DPI))
        img = plotter.screenshot(None, transparent_background=transparent, scale=k, return_img=True)
        size = (max(1, round(w * dpi / SCREEN_DPI)), max(1, round(h * dpi / SCREEN_DPI)))
        im = Image.fromarray(img)
        if im.size != size:
            im = im.resize(size, Image.Resampling.LANCZOS)
        im.save(tmp, format="PNG", dpi=(dpi, dpi))

    return _write_view(plotter, path, write, "the renderer produced no image")


def suffix_from_filter(path, selected_filter: str, allowed=(".png", ".svg", ".pdf")) -> Path:
    """The path a save dialog means: its own suffix when it is an allowed one (any case), else the
    chosen filter's suffix appended (``"SVG (*.svg)"`` -> ``.svg``).

    Parameters
    ----------
    path : str or Path
        What the user typed.
    selected_filter : str
        The dialog's chosen filter, e.g. ``"PDF (*.pdf)"``.
    """
    import re

    path = Path(path)
    if path.suffix.lower() in allowed:
        return path
    m = re.search(r"\*(\.[A-Za-z0-9]+)", selected_filter or "")
    suf = m.group(1).lower() if m else allowed[0]
    return path.with_name(path.name + suf)


def filter_suffixes(filters: str) -> tuple[str, ...]:
    """The suffixes a save dialog's filter string names, in its order:
    ``"CSV table (*.csv);;NumPy array (*.npy)"`` -> ``(".csv", ".npy")``."""
    import re

    return tuple(s.lower() for s in re.findall(r"\*(\.[A-Za-z0-9]+)", filters))


def vector_export_available() -> bool:
    """True: 3-D views are saved as vector graphics from the scene's data (no gl2ps needed)."""
    return True


def save_plotter_vector(plotter, path, *, title: str | None = None) -> Path:
    """Save a pyvista plotter's view as .svg, .pdf or .eps vector graphics, atomically.

    The view is redrawn from the scene's data through its camera
    (:func:`app.figures.view_vector.scene_figure`): points, lines and shaded polygons
    are vector primitives, the colour bar and legend are drawn again as a matplotlib
    colour bar and legend. No raster image is embedded. (VTK's gl2ps exporter, with
    the OpenGL2 backend of current VTK wheels, embeds the 3-D geometry as one image.)

    Parameters
    ----------
    plotter : pyvista plotter, open
    path : str or Path
        Suffix .svg, .pdf or .eps, in any case.
    title : str, optional
        A title drawn above the view.
    """
    _suffix(path, VECTOR_3D_FORMATS, "a 3-D view as vector graphics")
    if getattr(plotter, "render_window", None) is None:
        raise ValueError("this plotter is closed; save the view before closing it")
    from app.figures.view_vector import scene_figure

    return save_vector_figure(scene_figure(plotter, title=title), path)


def save_vector_figure(fig, path) -> Path:
    """Write a view's vector figure (:func:`app.figures.view_vector.scene_figure`) as .svg/.pdf/.eps,
    atomically. Touches no VTK or Qt object, so a worker thread may run it (most of an export's time)
    while the window stays responsive."""
    suf = _suffix(path, VECTOR_3D_FORMATS, "a 3-D view as vector graphics")
    from matplotlib import rc_context

    with rc_context({"svg.hashsalt": "lipspace", **EMBEDDED_FONTS}), atomic_write(path) as tmp:
        fig.savefig(tmp, format=suf.lstrip("."), metadata=_METADATA.get(suf, {}), facecolor=fig.get_facecolor())
    return Path(path)


def _write_view(plotter, path, write, empty_message: str) -> Path:
    """Run ``write(tmp)`` for an open plotter through an atomic write; an empty result is an OSError."""
    if getattr(plotter, "render_window", None) is None:
        raise ValueError("this plotter is closed; save the view before closing it")
    with atomic_write(path) as tmp:
        write(tmp)
        if not tmp.exists() or tmp.stat().st_size == 0:
            raise OSError(f"{path}: {empty_message}")
    return Path(path)
