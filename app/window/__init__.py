"""The parts of the explorer's main window (:class:`app.main_window.MainWindow`): its menus, sessions,
File › Export dialogs, and how it is launched and stopped."""
