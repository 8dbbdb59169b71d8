"""The README's Python API example runs as written (a doctest), and ``import engine`` stays light."""
from __future__ import annotations

import doctest
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _example() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Python API", 1)[1].split("\n## ", 1)[0]
    blocks = re.findall(r"```python\n(.*?)```", section, re.S)
    assert len(blocks) == 1, "the README's Python API section holds one python example"
    return blocks[0]


def test_readme_python_example_is_at_most_six_lines_and_runs(small_corpus):
    code = _example()
    assert sum(line.startswith(">>> ") for line in code.splitlines()) <= 6
    test = doctest.DocTestParser().get_doctest(code, {}, "README.md Python API", "README.md", 0)
    runner = doctest.DocTestRunner(optionflags=doctest.ELLIPSIS)
    runner.run(test)
    assert runner.failures == 0 and runner.tries >= 5, (runner.failures, runner.tries)


def test_import_engine_loads_no_numpy_and_every_public_name_resolves():
    code = ("import sys, engine\n"
            "light = 'numpy' not in sys.modules\n"
            "missing = [n for n in engine.__all__ if getattr(engine, n, None) is None]\n"
            "print(light, missing, 'PySide6' in sys.modules or 'pyvista' in sys.modules)\n")
    r = subprocess.run([sys.executable, "-c", code], cwd=ROOT, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    assert r.stdout.split() == ["True", "[]", "False"], r.stdout
