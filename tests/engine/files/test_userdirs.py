"""engine.files.userdirs: one rule for Lipspace's per-user folders."""
from pathlib import Path

import platformdirs

from engine.files.userdirs import user_dir


def test_the_variable_names_the_folder_else_the_platform_folder(monkeypatch, tmp_path):
    monkeypatch.setenv("LIPSPACE_CACHE_DIR", str(tmp_path / "c"))
    assert user_dir("cache", "LIPSPACE_CACHE_DIR") == tmp_path / "c"
    monkeypatch.setenv("LIPSPACE_STATE_DIR", "")  # empty counts as unset
    assert user_dir("state", "LIPSPACE_STATE_DIR") == Path(platformdirs.user_state_dir("lipspace"))
    monkeypatch.delenv("LIPSPACE_CACHE_DIR")
    assert user_dir("cache", "LIPSPACE_CACHE_DIR") == Path(platformdirs.user_cache_dir("lipspace"))
