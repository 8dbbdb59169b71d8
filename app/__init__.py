"""Lipspace application: the Qt/VTK explorer and the ``lipspace`` command line."""
