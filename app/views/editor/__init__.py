"""The parts of the trajectory editor (:class:`app.views.trajectory_editor.TrajectoryEditor`): its undo commands
and its timeline's control (cursor, selection, zoom, Praat's keys, tier edits)."""
