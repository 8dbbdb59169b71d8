"""Lipspace's per-user folders: an environment variable names one, else the platform's own.

One rule for every folder Lipspace keeps (the cache of generated talkers and fitted
manifolds, the autosaved session state): ``$LIPSPACE_<KIND>_DIR`` when set and not
empty, else ``platformdirs.user_<kind>_dir("lipspace")``.
"""
from __future__ import annotations

import os
from pathlib import Path

__all__ = ["user_dir"]


def user_dir(kind: str, env: str) -> Path:
    """The folder ``$env`` names, else the platform's user folder of ``kind`` for Lipspace.

    Parameters
    ----------
    kind : {"cache", "state"}
        Which platformdirs folder to fall back on (``user_cache_dir``, ``user_state_dir``).
    env : str
        The environment variable that overrides it (e.g. ``"LIPSPACE_CACHE_DIR"``).
    """
    value = os.environ.get(env)
    if value:
        return Path(value)
    import platformdirs

    return Path(getattr(platformdirs, f"user_{kind}_dir")("lipspace"))
