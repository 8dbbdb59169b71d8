"""engine never imports Qt, VTK, pyvista or matplotlib."""
import pkgutil
import subprocess
import sys
from pathlib import Path

import engine

FORBIDDEN = ("PySide6", "PyQt5", "PyQt6", "qtpy", "vtk", "vtkmodules", "pyvista", "pyvistaqt", "matplotlib")


def test_engine_imports_no_gui_toolkits():
    modules = sorted(m.name for m in pkgutil.walk_packages([str(Path(engine.__file__).parent)], "engine."))
    assert "engine.manifold.model" in modules and "engine.recordings.corpus" in modules
    code = (
        "import importlib, sys\n"
        f"for m in {modules!r}: importlib.import_module(m)\n"
        f"bad = sorted(k for k in sys.modules if k.split('.')[0] in {FORBIDDEN!r})\n"
        "print(','.join(bad))\n"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                         cwd=Path(engine.__file__).parents[1])
    assert out.stdout.strip() == "", f"engine imported GUI toolkits: {out.stdout}"
