"""The main window's File › Export dialogs: views, figures, trajectories, animation, tables, TextGrids."""
from __future__ import annotations

from pathlib import Path

from PySide6 import QtCore, QtWidgets

__all__ = ["ExportActions", "TRAJECTORY_FILTERS", "ANIMATION_FILTERS", "FIGURE_FILTERS"]

#: File > Export dialogs' filters; the suffixes each writes are read from them (app.figures.export.filter_suffixes)
TRAJECTORY_FILTERS = "CSV table (*.csv);;NumPy array (*.npy);;OBJ mesh sequence (*.obj);;PLY mesh sequence (*.ply)"
ANIMATION_FILTERS = "glTF binary (*.glb);;glTF (*.gltf);;MP4 video (*.mp4)"
FIGURE_FILTERS = "PNG image (*.png);;SVG (*.svg);;PDF (*.pdf)"


class ExportActions:
    """File › Export of :class:`app.main_window.MainWindow` (a mixin)."""

    def _view_plotter(self, which: str):
        """The plotter of the ``"manifold"`` or ``"lips"`` view."""
        return {"manifold": self.manifold_view.plotter, "lips": self.lip_view.plotter}[which]

    def export_view(self, which: str, path, *, dpi=None) -> Path:
        """Save the manifold or lip view as PNG (at ``dpi``) or SVG/PDF (vector, from the scene's data)."""
        from app.figures import save_plotter_image, save_plotter_vector

        plotter = self._view_plotter(which)
        if Path(path).suffix.lower() == ".png":
            return save_plotter_image(plotter, path, dpi=dpi)
        return save_plotter_vector(plotter, path)

    def _save_path(self, title: str, filters: str, start: str | None = None) -> Path | None:
        """Ask where to save (None: cancelled). A name typed without one of the suffixes ``filters``
        names takes the chosen filter's, so every File > Export dialog reads a typed name alike."""
        from app.figures.export import filter_suffixes, suffix_from_filter

        path, chosen = QtWidgets.QFileDialog.getSaveFileName(self, title, self.last_dir if start is None else start,
                                                             filters)
        return suffix_from_filter(path, chosen, filter_suffixes(filters)) if path else None

    def export_view_dialog(self, which):
        path = self._save_path(f"Export {which} view", FIGURE_FILTERS)
        if path:
            dpi = None
            if path.suffix.lower() == ".png":
                dpi, ok = QtWidgets.QInputDialog.getInt(self, "PNG resolution", "Dots per inch (96 = as on screen):",
                                                        150, 30, 1200, 10)
                if not ok:
                    return
                self._report(lambda: self.export_view(which, path, dpi=dpi), f"wrote {path}",
                             f"export the {which} view")
                return
            # vector: the scene is read here (VTK, GUI thread); writing the file, most of the time, runs in a worker
            from app.figures.export import save_vector_figure
            from app.figures.view_vector import scene_figure
            from app.user_messages import plain_errors
            from app.workers import run_task

            fig = scene_figure(self._view_plotter(which))
            run_task(plain_errors(lambda progress: save_vector_figure(fig, path), doing=f"export the {which} view"),
                     parent=self, title=f"Writing {path.name}", dialog=False,
                     on_done=lambda p: self.statusBar().showMessage(f"wrote {p}", 5000))
            self.statusBar().showMessage(f"writing {path.name}…")

    def export_figure_dialog(self, name):
        if self.state.manifold is None:
            return
        path = self._save_path(f"Export figure {name}", FIGURE_FILTERS, str(Path(self.last_dir) / f"{name}.png"))
        if not path:
            return
        from app.figures import UTTERANCE_FIGURES, export_figure
        from app.user_messages import plain_errors
        from app.workers import run_task

        m = self.state.manifold
        opts = {"utterance": self.state.utterance} if (name in UTTERANCE_FIGURES and self.state.utterance) else {}
        run_task(plain_errors(lambda progress: export_figure(name, m, path, **opts), doing=f"write figure {name}"),
                 parent=self, title=f"Rendering {name}",
                 on_done=lambda p: self.statusBar().showMessage(f"wrote {p}", 5000))

    def current_trajectory(self):
        """The trajectory File > Export writes: the synthetic one if any, else the original."""
        return self.state.synthetic if self.state.synthetic is not None else self.state.original

    def export_trajectory_dialog(self):
        traj = self.current_trajectory()
        if traj is None:
            QtWidgets.QMessageBox.information(self, "Lipspace", "No trajectory to export: choose an utterance or "
                                                               "synthesise one in the trajectory editor.")
            return
        path = self._save_path(f"Export trajectory ({traj.label})", TRAJECTORY_FILTERS)
        if path:
            from app.models.trajectories import export_trajectory

            path = str(path)
            self._report(lambda: export_trajectory(self.state.manifold, traj, path), f"wrote {path}",
                         "export the trajectory")

    def export_animation(self, path, progress=None) -> list[Path]:
        """The current trajectory as a glTF morph animation (.glb/.gltf, WAV beside) or an MP4."""
        from app.export.current import export_current_animation

        return export_current_animation(self.state, path, progress=progress)

    def export_animation_dialog(self):
        path = self._save_path("Export animation", ANIMATION_FILTERS)
        if not path:
            return
        path = str(path)
        from app.models.task_status import ProgressEstimate
        from engine.progress import Cancelled

        dlg = QtWidgets.QProgressDialog("Rendering the video…", "Cancel", 0, 100, self)
        dlg.setWindowModality(QtCore.Qt.WindowModality.WindowModal)
        dlg.setAutoReset(False)  # the last frame must not reset (and re-arm) it before the file is written
        dlg.setAutoClose(False)
        estimate = ProgressEstimate()

        def progress(stage, done, total):  # off-screen VTK stays in the GUI thread
            estimate.report(stage, done, total)
            dlg.setMaximum(total)
            dlg.setValue(min(done, total))
            dlg.setLabelText(f"Rendering the video: {estimate.text()}")
            QtWidgets.QApplication.processEvents()
            if dlg.wasCanceled():
                raise Cancelled("export cancelled")

        try:
            self._report(lambda: self.export_animation(path, progress), f"wrote {path}", "export the animation")
        except Cancelled:
            self.statusBar().showMessage("export cancelled; nothing was written", 5000)
        finally:
            # reset() stops the dialog's own show-after-4-s timer; a close alone left it to show again
            dlg.reset()
            dlg.hide()
            dlg.deleteLater()

    def export_clusters(self, path) -> Path:
        from engine.io.writers.export import write_table_csv

        return write_table_csv(path, self.clusters.table_rows())

    def export_clusters_dialog(self):
        if self.state.manifold is None:
            return
        path = self._save_path("Export cluster table", "CSV table (*.csv)")
        if path:
            path = str(path)
            self._report(lambda: self.export_clusters(path), f"wrote {path}", "export the cluster table")

    def _source_name(self) -> str:
        return str(self.state.source.get("path") or f"synthetic talker ({self.state.source.get('preset')})")

    def export_frame_table_dialog(self):
        """One row per frame, as ``lipspace table -o`` writes it (units in a .json beside it), in a worker."""
        if self.state.manifold is None:
            return
        from app.export.tables import export_frame_table, table_filters

        path = self._save_path("Export frame table", table_filters(), str(Path(self.last_dir) / "frames.csv"))
        if not path:
            return
        from app.user_messages import plain_errors
        from app.workers import run_task

        m, src = self.state.manifold, self._source_name()
        run_task(plain_errors(lambda progress: export_frame_table(m, path, source=src, progress=progress),
                              doing="export the frame table"), parent=self, title=f"Writing {path.name}",
                 on_done=lambda paths: self.statusBar().showMessage(
                     f"wrote {paths[0]} (units in {paths[1].name})", 8000))

    def export_textgrids_dialog(self):
        """One TextGrid per utterance into a folder, as ``lipspace table --textgrid`` writes them, in a worker."""
        m = self.state.manifold
        if m is None:
            return
        from app.export.tables import existing_textgrids, export_textgrids

        folder = QtWidgets.QFileDialog.getExistingDirectory(self, "Export TextGrids into folder", self.last_dir)
        if not folder:
            return
        there = existing_textgrids(m, folder)
        if there and QtWidgets.QMessageBox.question(
                self, "Lipspace", f"{len(there)} of the TextGrids exist already in {folder} (e.g. {there[0].name}). "
                                  "Replace them?") != QtWidgets.QMessageBox.StandardButton.Yes:
            return
        from app.user_messages import plain_errors
        from app.workers import run_task

        src = self._source_name()
        run_task(plain_errors(lambda progress: export_textgrids(m, folder, source=src, progress=progress),
                              doing="export the TextGrids"), parent=self, title="Writing TextGrids",
                 on_done=lambda files: self.statusBar().showMessage(f"wrote {len(files)} TextGrids to {folder}", 8000))
