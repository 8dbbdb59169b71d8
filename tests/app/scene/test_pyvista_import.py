"""pyvista's plotting package imported with matplotlib's pyplot and Agg canvas put off
(app.scene.pyvista_import): nothing of matplotlib's figure package until pyvista or Lipspace uses it,
and pyvista's functions that use them work as before."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import types

import pytest

FIGURE_MODULES = ("matplotlib.pyplot", "matplotlib.figure", "matplotlib.backends.backend_agg")


def _run(script: str) -> str:
    env = dict(os.environ, MPLBACKEND="Agg")  # pyplot's figures off screen, whatever the display
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(script)], capture_output=True, text=True, timeout=120,
                       env=env)
    assert r.returncode == 0, r.stderr
    return r.stdout


def test_the_scene_package_imports_pyvista_plotting_without_matplotlib_figures():
    out = _run(f"""
        import sys
        import app.scene
        print("PLOTTING", "pyvista.plotting" in sys.modules)
        print("LOADED", [m for m in {FIGURE_MODULES!r} if m in sys.modules])
        from pyvista.plotting import colors
        cycle = colors.get_matplotlib_theme_cycler()  # uses pyplot: imports the real one now
        import matplotlib.pyplot as plt
        print("SAME", cycle == plt.rcParams["axes.prop_cycle"], type(plt) is type(sys), hasattr(plt, "figure"))
        print("REAL", sys.modules["matplotlib.pyplot"] is plt, sys.modules["matplotlib"].pyplot is plt)
    """)
    assert "PLOTTING True" in out
    assert "LOADED []" in out
    assert "SAME True True True" in out
    assert "REAL True True" in out


def test_pyvistas_matplotlib_chart_still_renders_through_the_deferred_canvas():
    out = _run("""
        import sys
        from app.scene.pyvista_import import import_plotting
        plotting = import_plotting()
        from pyvista.plotting import charts
        print("DEFERRED", charts.FigureCanvasAgg.__module__ == "app.scene.pyvista_import")
        chart = plotting.ChartMPL()
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        print("CANVAS", type(chart._canvas) is FigureCanvasAgg, "matplotlib.figure" in sys.modules)
    """)
    assert "DEFERRED True" in out
    assert "CANVAS True True" in out


def test_nothing_is_put_off_when_pyplot_is_imported_first():
    out = _run("""
        import matplotlib.pyplot as plt
        from app.scene.pyvista_import import import_plotting
        import_plotting()
        from pyvista.plotting import charts, colors
        from matplotlib.backends.backend_agg import FigureCanvasAgg
        print("REAL", colors.plt is plt, charts.plt is plt, charts.FigureCanvasAgg is FigureCanvasAgg)
    """)
    assert "REAL True True True" in out


@pytest.fixture
def fake_module(tmp_path, monkeypatch):
    """A module ``lipspace_fake_heavy`` on the path with a class ``Canvas`` and a constant ``VALUE``."""
    (tmp_path / "lipspace_fake_heavy.py").write_text(
        "VALUE = 42\nclass Canvas:\n    def __init__(self, x):\n        self.x = x\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    monkeypatch.delitem(sys.modules, "lipspace_fake_heavy", raising=False)
    yield "lipspace_fake_heavy"
    sys.modules.pop("lipspace_fake_heavy", None)


def test_a_stand_in_hands_out_its_listed_names_as_callables_while_importing(fake_module, monkeypatch):
    from app.scene import pyvista_import as pi

    monkeypatch.setattr(pi, "DEFERRED", {fake_module: ("Canvas",)})
    monkeypatch.setitem(pi._importing, "thread", threading.get_ident())  # this thread is importing
    stand_in = pi._DeferredModule(fake_module)
    sys.modules[fake_module] = stand_in
    Canvas = stand_in.Canvas  # a listed name while the stand-in is in sys.modules: not imported yet
    assert isinstance(Canvas, types.FunctionType) and Canvas.__name__ == "Canvas"
    assert sys.modules[fake_module] is stand_in
    value = stand_in.VALUE  # any other name: the deferral ends, the real module is imported
    assert value == 42
    real = sys.modules[fake_module]
    assert real is not stand_in and isinstance(real, types.ModuleType) and not isinstance(real, pi._DeferredModule)
    made = Canvas(3)
    assert isinstance(made, real.Canvas) and made.x == 3
    assert stand_in.Canvas is real.Canvas  # after the import: the real attribute
    with pytest.raises(AttributeError):
        getattr(stand_in, "__wrapped__")  # noqa: B009 - the import system's dunder questions are not forwarded


def test_another_thread_meeting_a_stand_in_gets_the_real_module(fake_module, monkeypatch):
    """Only the thread importing pyvista's plotting package is handed deferred callables; any other ends the
    deferral and reads the real module."""
    from app.scene import pyvista_import as pi

    monkeypatch.setattr(pi, "DEFERRED", {fake_module: ("Canvas",)})
    monkeypatch.setitem(pi._importing, "thread", -1)  # another thread is importing
    stand_in = pi._DeferredModule(fake_module)
    sys.modules[fake_module] = stand_in
    Canvas = stand_in.Canvas
    real = sys.modules[fake_module]
    assert real is not stand_in and Canvas is real.Canvas and isinstance(Canvas, type)
