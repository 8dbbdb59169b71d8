"""The layers of pyproject.toml's import-linter contracts hold, and the contracts catch a breach."""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest
import tomllib

ROOT = Path(__file__).resolve().parents[1]

pytest.importorskip("importlinter", reason="import-linter is a test dependency (pip install -e .[test])")


def _lint(cwd: Path) -> subprocess.CompletedProcess:
    code = "import sys; from importlinter.cli import lint_imports; sys.exit(lint_imports())"
    return subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True, text=True, timeout=300,
                          env={"PYTHONPATH": str(cwd), "PATH": "/usr/bin:/bin", "HOME": str(cwd)})


def test_the_code_keeps_every_import_contract():
    r = _lint(ROOT)
    assert r.returncode == 0, r.stdout[-4000:] + r.stderr[-2000:]
    assert "broken" in r.stdout and " 0 broken" in r.stdout, r.stdout[-2000:]


def _tree(tmp_path: Path, files: dict) -> Path:
    config = tomllib.loads((ROOT / "pyproject.toml").read_text())["tool"]["importlinter"]
    lines = ["[tool.importlinter]", f"root_packages = {json.dumps(config['root_packages'])}",
             "include_external_packages = true"]
    for c in config["contracts"]:  # JSON strings and arrays are TOML's
        lines.append("[[tool.importlinter.contracts]]")
        lines += [f"{k} = {json.dumps(v)}" for k, v in c.items()]
    (tmp_path / "pyproject.toml").write_text("\n".join(lines) + "\n")
    app_layers = [f"app/{name.strip()}" for c in config["contracts"] if c.get("containers") == ["app"]
                  for layer in c["layers"] for name in layer.split("|")]
    for pkg in ("engine", "engine/io", "engine/files", "app", "app/models", "app/files", *app_layers):
        (tmp_path / pkg).mkdir(parents=True, exist_ok=True)
        (tmp_path / pkg / "__init__.py").write_text("")
    for name, text in files.items():
        (tmp_path / name).write_text(text)
    return tmp_path


@pytest.mark.parametrize("files, broken", [
    ({"engine/files/plot.py": "import matplotlib\n"}, "engine.files.plot -> matplotlib"),
    ({"app/models/view.py": "from PySide6 import QtWidgets\n"}, "app.models.view -> PySide6"),
    ({"engine/files/up.py": "import app.models\n"}, "engine.files.up -> app.models"),
    ({"engine/io/a.py": "import engine.files.b\n", "engine/files/b.py": "import engine.io.a\n"}, "No cycles"),
    ({"engine/io/_private.py": "", "engine/files/c.py": "import engine.io._private\n"}, "engine.io._private"),
    ({"app/models/pick.py": "import app.views\n"}, "app.models is not allowed to import app.views"),
    ({"app/files/load.py": "import app.window\n"}, "app.files is not allowed to import app.window"),
])
def test_each_contract_catches_its_breach(tmp_path, files, broken):
    r = _lint(_tree(tmp_path, files))
    assert r.returncode == 1, r.stdout[-3000:] + r.stderr[-2000:]
    assert broken in r.stdout, r.stdout[-3000:]
