"""File › Export figure: the size a figure is written at, and the window's figure exports.

Every figure the window writes goes through the functions ``lipspace figures`` uses: the
paper's figures through :func:`app.figures.export_figure`, the 3-D views through
:func:`app.figures.view_export.export_view` (PNG, SVG and PDF from one figure, so they carry the
labels of the screen). :class:`ExportOptionsDialog` asks for the width as a journal asks for
it (one column, 85 mm; two columns, 180 mm; any width from 40 to 260 mm; a view also as on
screen) and a PNG's resolution; the window keeps the last choice for the next export.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from PySide6 import QtWidgets

__all__ = ["ExportOptions", "ExportOptionsDialog", "export_view_dialog", "export_figure_dialog", "write_view",
           "write_figure", "FIGURE_FILTERS"]

#: the save dialog's filters of a figure (the suffixes :func:`app.figures.export.save_figure` writes)
FIGURE_FILTERS = "PNG image (*.png);;SVG (*.svg);;PDF (*.pdf)"


@dataclass(frozen=True)
class ExportOptions:
    """How a figure is written: ``width_mm`` (None: as on screen, views only) and a PNG's ``dpi``."""

    width_mm: float | None = 180.0
    dpi: float = 300.0

    @property
    def width_in(self) -> float | None:
        return None if self.width_mm is None else self.width_mm / 25.4


class ExportOptionsDialog(QtWidgets.QDialog):
    """Width (one column, two columns, a width of one's own, or as on screen) and PNG resolution."""

    def __init__(self, parent=None, *, options: ExportOptions | None = None, screen: bool = True,
                 png: bool = True, what: str = "figure"):
        super().__init__(parent)
        from app.figures.style import COLUMN_WIDTHS_MM, WIDTH_RANGE_MM

        self.setWindowTitle(f"Export {what}")
        options = options or ExportOptions()
        one, two = COLUMN_WIDTHS_MM["85mm"], COLUMN_WIDTHS_MM["180mm"]
        self.one = QtWidgets.QRadioButton(f"One journal column ({one:g} mm)")
        self.two = QtWidgets.QRadioButton(f"Two journal columns ({two:g} mm)")
        self.free = QtWidgets.QRadioButton("Width of my own:")
        self.screen = QtWidgets.QRadioButton("As on screen")
        self.width_mm = QtWidgets.QDoubleSpinBox()
        self.width_mm.setRange(*WIDTH_RANGE_MM)
        self.width_mm.setDecimals(0)
        self.width_mm.setSuffix(" mm")
        self.width_mm.setValue(options.width_mm if options.width_mm is not None else two)
        self.dpi = QtWidgets.QSpinBox()
        self.dpi.setRange(72, 1200)
        self.dpi.setSingleStep(50)
        self.dpi.setSuffix(" dpi")
        self.dpi.setValue(int(round(options.dpi)))
        self.dpi.setToolTip("Resolution of a PNG (SVG and PDF are vector graphics; their text stays text)")
        self.screen.setVisible(screen)
        if options.width_mm is None and screen:
            self.screen.setChecked(True)
        elif options.width_mm is not None and abs(options.width_mm - one) < 0.5:
            self.one.setChecked(True)
        elif options.width_mm is not None and abs(options.width_mm - two) < 0.5:
            self.two.setChecked(True)
        else:
            self.free.setChecked(True)
        self.free.toggled.connect(self.width_mm.setEnabled)
        self.width_mm.setEnabled(self.free.isChecked())
        form = QtWidgets.QFormLayout()
        box = QtWidgets.QVBoxLayout()
        for b in (self.one, self.two):
            box.addWidget(b)
        row = QtWidgets.QHBoxLayout()
        row.addWidget(self.free)
        row.addWidget(self.width_mm)
        row.addStretch(1)
        box.addLayout(row)
        box.addWidget(self.screen)
        form.addRow("Width:", box)
        self.dpi_label = QtWidgets.QLabel("PNG resolution:")
        form.addRow(self.dpi_label, self.dpi)
        self.dpi.setVisible(png)
        self.dpi_label.setVisible(png)
        note = QtWidgets.QLabel("Text is set at 7–8 pt for the width chosen (never below 6 pt), as journals ask.")
        note.setWordWrap(True)
        buttons = QtWidgets.QDialogButtonBox(QtWidgets.QDialogButtonBox.StandardButton.Ok
                                             | QtWidgets.QDialogButtonBox.StandardButton.Cancel)
        buttons.accepted.connect(self.accept)
        buttons.rejected.connect(self.reject)
        lay = QtWidgets.QVBoxLayout(self)
        lay.addLayout(form)
        lay.addWidget(note)
        lay.addWidget(buttons)

    def options(self) -> ExportOptions:
        from app.figures.style import COLUMN_WIDTHS_MM

        if self.screen.isChecked() and self.screen.isVisibleTo(self):
            width = None
        elif self.one.isChecked():
            width = COLUMN_WIDTHS_MM["85mm"]
        elif self.two.isChecked():
            width = COLUMN_WIDTHS_MM["180mm"]
        else:
            width = float(self.width_mm.value())
        return ExportOptions(width_mm=width, dpi=float(self.dpi.value()))


def _ask(window, *, screen: bool, png: bool, what: str) -> ExportOptions | None:
    """The options for this export (None: cancelled); the window keeps them as the next default."""
    last = getattr(window, "export_options", None)
    if last is not None and last.width_mm is None and not screen:
        last = ExportOptions(dpi=last.dpi)
    dlg = ExportOptionsDialog(window, options=last, screen=screen, png=png, what=what)
    if dlg.exec() != QtWidgets.QDialog.DialogCode.Accepted:
        return None
    window.export_options = dlg.options()
    return window.export_options


def write_view(window, which: str, path, options: ExportOptions, *, on_done=None) -> None:
    """Write the ``"manifold"`` or ``"lips"`` view to ``path``: the figure is read from the scene here (GUI
    thread), written in a worker (most of the time)."""
    from app.figures.export import save_figure
    from app.figures.view_export import view_figure
    from app.user_messages import plain_errors
    from app.workers import run_task

    path = Path(path)
    fig = view_figure(window._view_plotter(which), width=options.width_in)
    run_task(plain_errors(lambda progress: save_figure(fig, path, dpi=options.dpi), doing=f"export the {which} view"),
             parent=window, title=f"Writing {path.name}", dialog=False,
             on_done=on_done or (lambda p: window.statusBar().showMessage(f"wrote {p}", 5000)))
    window.statusBar().showMessage(f"writing {path.name}…")


def write_figure(window, name: str, path, options: ExportOptions, *, on_done=None) -> None:
    """Write figure ``name`` of the window's manifold to ``path`` at ``options`` (in a worker), with the
    session's palette and, for the figures that show one, the window's utterance."""
    from app.figures import UTTERANCE_FIGURES, export_figure
    from app.user_messages import plain_errors
    from app.workers import run_task

    state = window.state
    m = state.manifold
    opts = {"utterance": state.utterance} if (name in UTTERANCE_FIGURES and state.utterance) else {}
    palette = getattr(state, "palette", None)
    if palette is not None:
        opts["palette"] = palette
    width = options.width_in if options.width_in is not None else None
    run_task(plain_errors(lambda progress: export_figure(name, m, path, width=width, dpi=options.dpi, **opts),
                          doing=f"write figure {name}"), parent=window, title=f"Rendering {name}",
             on_done=on_done or (lambda p: window.statusBar().showMessage(f"wrote {p}", 5000)))


def export_view_dialog(window, which: str) -> None:
    """File › Export figure › a view: where, at which width and resolution; then :func:`write_view`."""
    path = window._save_path(f"Export {which} view", FIGURE_FILTERS)
    if not path:
        return
    options = _ask(window, screen=True, png=path.suffix.lower() == ".png", what=f"the {which} view")
    if options is not None:
        write_view(window, which, path, options)


def export_figure_dialog(window, name: str) -> None:
    """File › Export figure › a paper figure: where, at which width (and PNG resolution); then
    :func:`write_figure`."""
    if window.state.manifold is None:
        return
    path = window._save_path(f"Export figure {name}", FIGURE_FILTERS, str(Path(window.last_dir) / f"{name}.png"))
    if not path:
        return
    options = _ask(window, screen=False, png=path.suffix.lower() == ".png", what=f"figure {name}")
    if options is not None:
        write_figure(window, name, path, options)
