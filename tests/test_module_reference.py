"""The generated module reference lists every module of engine/ and app/, each with a docstring."""
import ast
import importlib.util
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"


def _extension():
    spec = importlib.util.spec_from_file_location("module_reference", DOCS / "_ext" / "module_reference.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _source_modules(root: Path) -> dict[str, Path]:
    """Dotted name → file of every Python source under engine/ and app/ (found apart from the extension)."""
    found = {}
    for top in ("engine", "app"):
        for path in (root / top).rglob("*.py"):
            if "__pycache__" in path.parts:
                continue
            parts = list(path.relative_to(root).with_suffix("").parts)
            if parts[-1] == "__init__":
                parts.pop()
            found[".".join(parts)] = path
    return found


def _listed(page: str) -> list[str]:
    """The names in the page's autosummary tables that write a page each (``:toctree:``)."""
    names = []
    for block in re.findall(r"^\.\. autosummary::\n((?:   .*\n|\n)*)", page, flags=re.M):
        assert re.search(r"^   :toctree: \S+", block, flags=re.M), block
        names += [line.strip() for line in block.splitlines() if line.strip() and not line.strip().startswith(":")]
    return names


def test_every_module_is_in_the_reference_once():
    listed = _listed(_extension().page_text(_extension().package_modules()))
    sources = _source_modules(ROOT)
    assert len(sources) > 200  # the walk found the packages
    assert len(listed) == len(set(listed)), sorted(n for n in set(listed) if listed.count(n) > 1)
    missing = sorted(set(sources) - set(listed))
    extra = sorted(set(listed) - set(sources))
    assert not missing, f"modules missing from the reference: {missing}"
    assert not extra, f"the reference lists modules that have no file: {extra}"


def test_every_module_has_a_docstring_whose_first_line_says_what_it_does():
    bare = []
    for name, path in sorted(_source_modules(ROOT).items()):
        doc = ast.get_docstring(ast.parse(path.read_text(encoding="utf-8"), filename=str(path)))
        if not doc or not doc.splitlines()[0].strip():
            bare.append(f"{path.relative_to(ROOT)} ({name})")
    assert not bare, "modules without a docstring (its first line is the reference's summary): " + ", ".join(bare)


def test_a_new_module_is_listed_without_editing_the_docs(tmp_path):
    ext = _extension()
    for folder in ("engine", "engine/graph", "app", "app/views/manifold"):
        (tmp_path / folder).mkdir(parents=True, exist_ok=True)
        (tmp_path / folder / "__init__.py").write_text('"""A package."""\n')
    (tmp_path / "engine" / "graph" / "new_concept.py").write_text('"""A new concept."""\n')
    (tmp_path / "app" / "views" / "stray.txt").write_text("not a module")
    groups = ext.package_modules(tmp_path)
    # app/views has no __init__.py here: no package of its own, but its sub-package is one
    assert list(groups) == ["engine", "engine.graph", "app", "app.views.manifold"]
    assert groups["engine.graph"] == ["engine.graph", "engine.graph.new_concept"]
    assert set(_listed(ext.page_text(groups))) == set(_source_modules(tmp_path))


def test_the_docs_build_the_generated_page():
    conf = (DOCS / "conf.py").read_text(encoding="utf-8")
    assert '"module_reference"' in conf
    index = (DOCS / "index.rst").read_text(encoding="utf-8")
    assert re.search(r"^   generated/modules$", index, flags=re.M)
    assert _extension().PAGE.as_posix() == "generated/modules.rst"
