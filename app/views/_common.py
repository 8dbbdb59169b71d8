"""Small Qt helpers shared by the views."""
from __future__ import annotations

import math
from contextlib import contextmanager

__all__ = ["blocked", "elided_label", "make_plotter", "camera_of", "set_camera", "close_plotter",
           "connect_all", "disconnect_all",
           "RenderScheduler", "Throttle", "READOUT_INTERVAL_S", "drawing_frame"]

#: seconds between two repaints of the readouts that follow playback (caption, slider, the
#: editor's timeline cursor): each repaint of an ordinary widget composes the main window
#: and, measured, often the 3-D views' windows with it (docs/DECISIONS.md, I2); the
#: manifold view's playback markers render at the same rate
READOUT_INTERVAL_S = 0.5


@contextmanager
def blocked(*widgets):
    """Block the Qt signals of ``widgets`` while syncing them to the state."""
    old = [w.blockSignals(True) for w in widgets]
    try:
        yield
    finally:
        for w, o in zip(widgets, old):
            w.blockSignals(o)


def elided_label(text: str = ""):
    """A one-line QLabel that elides its text at the right ("…") when narrow, the whole text in its tooltip.

    Never wraps onto a second line under a dock's tab bar, never widens its dock, never cuts a
    word to a fragment without saying so.
    """
    from PySide6 import QtCore, QtWidgets

    class _Elided(QtWidgets.QLabel):
        def __init__(self, text):
            super().__init__()
            self._full = ""
            self.setSizePolicy(QtWidgets.QSizePolicy.Policy.Ignored, QtWidgets.QSizePolicy.Policy.Fixed)
            self.setText(text)

        def setText(self, text):  # noqa: N802 - Qt override
            self._full = str(text)
            self.setToolTip(self._full)
            self._elide()
            self.updateGeometry()  # a layout that gives it its size hint asks again

        def text(self):  # the whole text, as set
            return self._full

        def resizeEvent(self, event):  # noqa: N802 - Qt override
            super().resizeEvent(event)
            self._elide()

        def minimumSizeHint(self):  # noqa: N802 - Qt override
            return QtCore.QSize(max(self.minimumWidth(), 0), super().minimumSizeHint().height())

        def sizeHint(self):  # noqa: N802 - Qt override: the whole text's width, within the label's limits
            want = self.fontMetrics().horizontalAdvance(self._full) + 8
            return QtCore.QSize(min(max(want, self.minimumWidth()), self.maximumWidth()),
                                super().sizeHint().height())

        def _elide(self):
            shown = self.fontMetrics().elidedText(self._full, QtCore.Qt.TextElideMode.ElideRight, max(self.width(), 1))
            QtWidgets.QLabel.setText(self, shown)

    return _Elided(text)


def make_plotter(parent, shape=(1, 1)):
    """A pyvistaqt QtInteractor with the explorer's look (white background, paper style); ``shape``: its grid
    of renderers (the small multiples')."""
    from app.scene.pyvista_import import import_plotting

    import_plotting()  # before pyvistaqt, which imports pyvista's plotting package
    from pyvistaqt import QtInteractor

    # no auto-update timer: views render on demand (RenderScheduler), so an idle window costs nothing.
    # No multisampling: with software OpenGL (Mesa llvmpipe) 4x MSAA costs 20-40 % of every frame
    # (docs/DECISIONS.md, H3); points are drawn as shaded spheres, which need none.
    plotter = QtInteractor(parent, auto_update=False, multi_samples=0, shape=tuple(shape), border=False)
    plotter.set_background("white")
    # plain alpha blending for the few translucent things (zero-velocity plane, convex ellipsoids drawn
    # front faces only): order-independent transparency adds full-window passes to every frame
    for ren in plotter.renderers:
        ren.SetUseOIT(False)
    _native_when_shown(plotter.interactor)
    return plotter


def _native_when_shown(widget) -> None:
    """Give a 3-D widget a native window of its own once it is first shown.

    Qt composes a window holding OpenGL widgets through OpenGL, the whole window at every
    repaint of any of its widgets; in software OpenGL (Mesa llvmpipe) that composition
    cost more than a lip frame itself (15-25 ms at 1400x900). With each 3-D widget in a
    native window of its own, a render repaints that window alone, and a label or slider
    repaint in the main window is a plain raster update (docs/DECISIONS.md,
    I2). Requested once on screen: asked for at construction it measured
    no better than none.
    """
    from PySide6 import QtCore

    class _OnShow(QtCore.QObject):
        def eventFilter(self, obj, event):  # noqa: N802 - Qt override
            if event.type() == QtCore.QEvent.Type.Show:
                obj.removeEventFilter(self)
                if not obj.testAttribute(QtCore.Qt.WidgetAttribute.WA_NativeWindow):
                    obj.winId()
            return False

    widget._lipspace_native_filter = _OnShow(widget)
    widget.installEventFilter(widget._lipspace_native_filter)


def camera_of(plotter) -> list:
    """The camera as [[position], [focal point], [view up]] (JSON-ready)."""
    return [[float(x) for x in row] for row in plotter.camera_position]


def set_camera(plotter, cam) -> None:
    """Restore a camera saved by :func:`camera_of` (ignored when malformed)."""
    try:
        rows = [[float(x) for x in row] for row in cam]
    except (TypeError, ValueError):
        return
    if len(rows) == 3 and all(len(r) == 3 and all(math.isfinite(x) for x in r) for r in rows) and rows[0] != rows[1]:
        plotter.camera_position = rows
        plotter.render()


def close_plotter(plotter) -> None:
    """Close a QtInteractor's render window (safe to call twice)."""
    if not getattr(plotter, "_lipspace_closed", False):
        plotter._lipspace_closed = True
        plotter.close()


class RenderScheduler:
    """Coalesce render requests: many state events in one pass give one render.

    ``request()`` marks the plotter's widget dirty at once (``update()``), so its
    ``paintGL`` joins the next paint of the window: the scene is rendered exactly once
    (calling ``plotter.render()`` instead would render twice: once into VTK's framebuffer,
    and again in the ``paintGL`` its frame event schedules), and Qt composes it with every
    other widget changed in the same pass into one window update (marking it dirty from a
    timer instead let the other widgets' paint be composed first, then the view's: two
    compositions, ~20 ms each in software GL). The request stays pending until the end of
    the pass (a zero-time timer), so many state events in one pass count one render.
    ``request(min_interval_s=...)`` throttles: the render waits until that long after the
    previous one (the manifold view follows playback this way while the lip view renders
    every frame).
    ``flush(sync=True)`` renders and composes now (always: a ``repaint()`` is deferred by
    Qt when the window was composed less than a screen refresh before).

    Attributes
    ----------
    n_renders : int
        Renders requested of the widget so far (flushes that found a request pending).
    last_flush : float
        ``time.perf_counter()`` of the last flush (0 before any).
    last_duration : float
        Seconds the last synchronous flush took to render and compose (0 before any).
    """

    def __init__(self, plotter):
        from PySide6 import QtCore

        self.plotter = plotter
        self.pending = False
        self.n_renders = 0
        self.last_flush = 0.0
        self.last_duration = 0.0
        self._sync_next = False
        self._timer = QtCore.QTimer()
        # precise: a coarse timer (Qt's default) may fire up to 5 % of its interval early,
        # 25 ms of a 0.5-s throttle, and so render sooner than ``min_interval_s``
        self._timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self._timer.setSingleShot(True)
        self._timer.setInterval(0)
        self._timer.timeout.connect(lambda: self.flush(sync=self._sync_next))

    def request(self, *, min_interval_s: float = 0.0) -> None:
        """Ask for one render soon (no sooner than ``min_interval_s`` after the previous flush).

        A throttled render is painted on its own (``flush(sync=True)`` from its timer), so
        it never joins, and delays, a frame another view paints at once (playback).
        """
        import time

        wait_ms = 0
        if min_interval_s > 0:
            wait_ms = max(0, int(round(1000 * (self.last_flush + min_interval_s - time.perf_counter()))))
            wait_ms = min(wait_ms, 2**31 - 1)
        if self.pending:
            if min_interval_s <= 0 and self._sync_next:
                self._sync_next = False
                self._mark()  # an unthrottled request overtakes a throttled one
            return
        self.pending = True
        self._sync_next = min_interval_s > 0
        if self._sync_next:
            self._timer.start(wait_ms)
        else:
            self._mark()

    def _mark(self) -> None:
        """Mark the widget dirty now (it paints with the window's next update); the request is done
        when the pass ends."""
        import time

        self.n_renders += 1
        self.last_flush = time.perf_counter()
        if not getattr(self.plotter, "_lipspace_closed", False):
            self.plotter.interactor.update()
        self._timer.start(0)

    def flush(self, *, sync: bool = False) -> None:
        """Render now if a request is pending (``sync``: paint and compose before returning)."""
        import time

        if not self.pending:
            return
        marked = not self._sync_next  # an unthrottled request has marked the widget dirty already (_mark)
        self.pending = False
        self._sync_next = False
        self._timer.stop()
        if getattr(self.plotter, "_lipspace_closed", False) or (marked and not sync):
            return  # marked: the widget is dirty already and paints with the window
        if not marked:
            self.n_renders += 1
            self.last_flush = time.perf_counter()
        widget = self.plotter.interactor
        if sync:
            from PySide6 import QtCore

            # not widget.repaint(): in a window Qt composes through OpenGL, a repaint() less than
            # a screen refresh after the window's last composition is silently deferred to the next
            # turn of the event loop (Qt's anti-starvation rule), where other widgets' paints join it
            widget.update()
            QtCore.QCoreApplication.sendPostedEvents(widget.window(), int(QtCore.QEvent.Type.UpdateRequest.value))
            self.last_duration = time.perf_counter() - self.last_flush
        else:
            widget.update()

    def stop(self) -> None:
        self._timer.stop()
        self.pending = False


#: fraction of a slot a readout held by playback frames waits past the slot's start for a frame
#: to run after, before it runs on its own (see drawing_frame)
FRAME_GRACE = 0.25

#: throttles holding a call until the playback frame being drawn is on screen (see drawing_frame)
_after_frame: list = []
_frame_depth = 0


@contextmanager
def drawing_frame():
    """Draw one playback frame: readouts called meanwhile show only once it is on screen.

    A :class:`Throttle` called inside holds its call (even the first of a slot) until the
    outermost ``drawing_frame`` exits; then the held calls whose slot has come run, and
    their layout and repaint are done at once (one composition of the main window, right
    after the frame's swap). Calls of a slot not yet come wait for the first frame drawn
    after its start (or, when none is, ``FRAME_GRACE`` of a slot later). A readout's
    repaint composes the whole main window (15-25 ms in software OpenGL): painted in the
    same pass as the lip frame it made that frame late by as much (docs/DECISIONS.md,
    I3).
    """
    global _frame_depth
    _frame_depth += 1
    try:
        yield
    finally:
        _frame_depth -= 1
        if _frame_depth == 0 and _after_frame:
            from PySide6 import QtCore

            for throttle in list(_after_frame):
                throttle._after_frame()  # leaves the list once its call has run
            for kind in (QtCore.QEvent.Type.LayoutRequest, QtCore.QEvent.Type.UpdateRequest):
                QtCore.QCoreApplication.sendPostedEvents(None, int(kind.value))


class Throttle:
    """Call ``callback`` at most once per slot of ``interval_s``, always ending on the latest arguments.

    Time is cut into slots of ``interval_s`` on the clock (``floor(t / interval_s)``). The
    first call in a slot runs at once; later calls in the same slot are held (the latest
    replaces any held one) and run at the start of the next slot. Readouts that follow
    playback (caption, slider, timeline cursor) each go through one: all throttles of one
    interval share the slot boundaries, so they repaint in the same turn of the event loop
    — one composition of the window every ``interval_s`` instead of one per readout per
    frame. In software OpenGL a composition of the whole window costs more than a lip
    frame (docs/DECISIONS.md, I2). Called while a playback
    frame is drawn (:func:`drawing_frame`), the call runs just after that frame is on
    screen.

    Parameters
    ----------
    callback : callable
    interval_s : float
        Slot length in seconds (> 0).
    clock : callable() -> float, default=time.monotonic
    parent : QObject, optional
        Owner of the timer (a held call dies with it).
    """

    def __init__(self, callback, interval_s: float, *, clock=None, parent=None):
        import time

        from PySide6 import QtCore

        if not interval_s > 0:
            raise ValueError(f"interval_s must be a positive number of seconds, got {interval_s!r}")
        self.callback = callback
        self.interval_s = float(interval_s)
        self.clock = clock or time.monotonic
        self.last_slot = None
        self._held = None
        self._timer = QtCore.QTimer(parent)
        self._timer.setTimerType(QtCore.Qt.TimerType.PreciseTimer)
        self._timer.setSingleShot(True)
        self._timer.timeout.connect(self.flush)
        self._timer.destroyed.connect(lambda *_a: self._unlist())  # its owner is gone: never run it again

    def __call__(self, *args) -> None:
        import math

        now = self.clock()
        slot = math.floor(now / self.interval_s)
        if _frame_depth:  # a playback frame is being drawn: run after it (drawing_frame)
            self._held = args
            if self not in _after_frame:
                _after_frame.append(self)
            return
        if slot != self.last_slot:
            self._timer.stop()
            self._held = None
            self.last_slot = slot
            self.callback(*args)
            return
        self._held = args
        if not self._timer.isActive():
            self._timer.start(max(1, math.ceil(1000 * ((slot + 1) * self.interval_s - now))))

    def _after_frame(self) -> None:
        """A playback frame is on screen: run the held call if its slot has come, else wait for a later frame."""
        import math

        if self._held is None:
            self._unlist()
            return
        now = self.clock()
        slot = math.floor(now / self.interval_s)
        if slot != self.last_slot:
            self.flush()
        else:  # the first frame after the slot's start runs it; this timer in case none comes
            wait = (slot + 1 + FRAME_GRACE) * self.interval_s - now
            self._timer.start(max(1, math.ceil(1000 * wait)))

    def flush(self) -> None:
        """Run the held call now (nothing when none is held)."""
        import math

        self._timer.stop()
        self._unlist()
        if self._held is not None:
            args, self._held = self._held, None
            self.last_slot = math.floor(self.clock() / self.interval_s)
            self.callback(*args)

    def cancel(self) -> None:
        """Drop the held call."""
        self._timer.stop()
        self._unlist()
        self._held = None

    def _unlist(self) -> None:
        if self in _after_frame:
            _after_frame.remove(self)


def connect_all(connections) -> list:
    """Connect each ``(event, callback)`` pair of a view to the state; returns the list."""
    connections = list(connections)
    for event, cb in connections:
        event.connect(cb)
    return connections


def disconnect_all(connections) -> None:
    """Undo :func:`connect_all` (pairs already gone are skipped)."""
    for event, cb in connections:
        try:
            event.disconnect(cb)
        except ValueError:
            pass
