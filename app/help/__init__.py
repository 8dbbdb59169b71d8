"""The help the program ships: the user guide, the keyboard shortcut sheet and the About text (Qt-free).

The user guide is package data (``app/help/user_guide.html``), read from the installed
package and shown in the window by :mod:`app.help.browser`; nothing is fetched from a
network.
"""
from __future__ import annotations

import html
from importlib import resources

__all__ = ["SHORTCUTS", "CITATION", "user_guide_html", "shortcut_sheet_html", "about_html"]

#: (keys, where, what) of every keyboard shortcut of the window; tests check each against the window
SHORTCUTS = (
    ("Ctrl+O", "window", "Open a corpus, manifold or recording"),
    ("Ctrl+S", "window", "Save the session"),
    ("Ctrl+Q", "window", "Quit"),
    ("Ctrl+Z", "window", "Undo the last edit: the editor's targets and tiers, or the view's settings"),
    ("Ctrl+Shift+Z", "window", "Redo it (Ctrl+Y too)"),
    ("F1", "window", "The user guide"),
    ("F", "window", "Frame the selection: bring the ticked clusters and the selection into view"),
    ("Esc", "manifold view", "Clear the selection (frame, state, target, path); nothing else"),
    ("Shift+click", "manifold view", "Path from the selected state to the clicked one"),
    ("Ctrl+T", "trajectory editor", "Add the selected state as a target at the cursor"),
    ("Delete", "trajectory editor", "Remove the chosen target"),
    ("Space", "trajectory editor", "Play / pause"),
    ("Tab", "editor timeline", "Play the selection, or the visible part, and stop (again: stop)"),
    ("Shift+Tab", "editor timeline", "Play from the cursor to the end"),
    ("Ctrl+I / Ctrl+O", "editor timeline", "Zoom in / out"),
    ("Ctrl+N / Ctrl+A", "editor timeline", "Show the selection / show all"),
    ("Esc", "editor timeline", "Clear the time selection"),
    ("Left / Right", "editor timeline", "Step one frame back / forward"),
    ("Wheel, + / -", "editor timeline", "Zoom the timeline in / out"),
)

#: how to cite the method (from the paper's title page)
CITATION = ("J. D. Edge, A. Hilton and P. Jackson. Parameterisation of Speech Lip Movements. "
            "Centre for Vision, Speech and Signal Processing, University of Surrey, Guildford, UK.")


def user_guide_html() -> str:
    """The user guide page (HTML) shipped with the program."""
    return resources.files(__package__).joinpath("user_guide.html").read_text(encoding="utf-8")


def shortcut_sheet_html() -> str:
    """The keyboard shortcuts as an HTML table."""
    rows = "".join(f"<tr><td><b>{html.escape(k)}</b></td><td>{html.escape(w)}</td><td>{html.escape(t)}</td></tr>"
                   for k, w, t in SHORTCUTS)
    return ("<html><body><h1>Keyboard shortcuts</h1><table cellpadding='4'>"
            "<tr><th align='left'>Keys</th><th align='left'>Where</th><th align='left'>What</th></tr>"
            f"{rows}</table></body></html>")


def about_html(version: str) -> str:
    """The About box: what Lipspace is, its version and how to cite the method."""
    return (f"<h3>Lipspace {html.escape(version)}</h3>"
            "<p>An explorer of the visual speech manifold: lip shape and its velocity in one "
            "low-dimensional space, its future and past hemispheres, phone clusters and trajectory "
            "synthesis along the manifold.</p>"
            "<p><b>How to cite the method</b><br>" + html.escape(CITATION) + "</p>"
            "<p>Help › User guide (F1) explains the window.</p>")
