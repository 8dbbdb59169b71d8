"""Qt-free session files, autosave, reading sources and the manifold cache."""
