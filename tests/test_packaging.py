"""The package carries what the program reads: every package listed, every data file declared as package data.

``.ci/check_wheel`` builds the wheel and the sdist and runs them installed; these checks fail
sooner, on the configuration itself.
"""
from __future__ import annotations

import fnmatch
import subprocess
from pathlib import Path

import pytest

tomllib = pytest.importorskip("tomllib")

ROOT = Path(__file__).resolve().parents[1]


def _setuptools() -> dict:
    return tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["tool"]["setuptools"]


def _tracked(*folders) -> list[Path]:
    """The files of ``folders`` git tracks (every file there when this is no git checkout)."""
    try:
        out = subprocess.run(["git", "ls-files", *folders], cwd=ROOT, capture_output=True, text=True, check=True,
                             timeout=60).stdout.split()
        return [ROOT / f for f in out]
    except (OSError, subprocess.SubprocessError):
        return [p for f in folders for p in (ROOT / f).rglob("*") if p.is_file() and "__pycache__" not in p.parts]


def test_every_package_is_listed_and_assets_is_installed_as_engine_assets():
    cfg = _setuptools()
    found = sorted(".".join(p.relative_to(ROOT).parts[:-1]) for pkg in ("engine", "app")
                   for p in (ROOT / pkg).rglob("__init__.py"))
    listed = cfg["packages"]
    assert len(listed) == len(set(listed))
    assert sorted(set(listed) - {"engine.assets"}) == found, "add the new package to [tool.setuptools] packages"
    assert "engine.assets" in listed and cfg["package-dir"] == {"engine.assets": "assets"}
    assert (ROOT / "assets" / "__init__.py").is_file()


def test_every_file_the_program_reads_is_package_data():
    data = _setuptools()["package-data"]
    files = [p for p in _tracked("app", "engine", "assets") if p.suffix not in (".py", ".pyc")]
    assert files  # the help page, the colour tables, the assets
    for f in files:
        rel = f.relative_to(ROOT)
        pkg = "engine.assets" if rel.parts[0] == "assets" else ".".join(rel.parts[:-1])
        assert any(fnmatch.fnmatch(f.name, pat) for pat in data.get(pkg, [])), \
            f"{rel}: not package data of {pkg} in pyproject.toml ([tool.setuptools.package-data])"


def test_assets_are_read_from_the_installed_package():
    from importlib import resources

    from engine.files.assets import asset_path, assets_dir

    try:
        root = resources.files("engine.assets")
    except ModuleNotFoundError:
        pytest.skip("Lipspace is not installed here (a bare checkout on PYTHONPATH): assets/ is read directly")
    assert assets_dir() == Path(str(root))
    assert asset_path("wordlist.txt").read_text(encoding="utf-8") == \
        root.joinpath("wordlist.txt").read_text(encoding="utf-8")
    with pytest.raises(FileNotFoundError, match="no-such-asset.txt.*reinstall"):
        asset_path("no-such-asset.txt")
