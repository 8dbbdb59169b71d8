"""The files Lipspace ships: phone sets, the synthetic talker's word list and its fitted manifold.

This folder is the package ``engine.assets`` once installed (``pyproject.toml`` maps it);
:mod:`engine.files.assets` finds the files.
"""
