"""Whether a window can open here, asked before Qt is (Qt-free).

Qt aborts the whole process (a core dump and "Reinstalling the application may fix this
problem") when ``DISPLAY`` names no X server, or ``WAYLAND_DISPLAY`` a socket where no
compositor listens. :func:`display_problem` tries the connection Qt would make, the way Qt
makes it (libxcb's own ``xcb_connect``, so that the host, the screen and the X
authority are those Qt would use; a plain socket where libxcb cannot be loaded), and
returns what is wrong in words, for ``lipspace explore`` to say before exiting.
"""
from __future__ import annotations

import os
import re
import socket
import sys

__all__ = ["display_problem", "x_server_answers", "wayland_answers", "HEADLESS_PLATFORMS"]

#: Qt platforms that need no display server (QT_QPA_PLATFORM)
HEADLESS_PLATFORMS = ("offscreen", "minimal", "vnc", "eglfs", "linuxfb", "vkkhrdisplay")
#: seconds a TCP display may take to answer
TIMEOUT_S = 3.0


def _x_socket_check(display: str) -> str | None:
    """Why no X server answers at ``display`` (a plain connection, without libxcb), or None."""
    m = re.fullmatch(r"(?:(?P<host>[^:/]*)(?:/(?P<proto>\w+))?:)?:?(?P<num>\d+)(?:\.\d+)?", display.strip())
    if m is None:
        return f"DISPLAY is {display!r}, which is not of the form [host]:number[.screen]"
    host, num = m.group("host") or "", int(m.group("num"))
    try:
        if host in ("", "unix"):
            with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
                s.settimeout(TIMEOUT_S)
                for path in (f"\0/tmp/.X11-unix/X{num}", f"/tmp/.X11-unix/X{num}"):
                    try:
                        s.connect(path)
                        return None
                    except OSError:
                        continue
            return f"DISPLAY is {display!r} but no X server listens at /tmp/.X11-unix/X{num}"
        with socket.create_connection((host, 6000 + num), timeout=TIMEOUT_S):
            return None
    except OSError as exc:
        return f"DISPLAY is {display!r} but no X server answers there ({exc.strerror or exc})"


def x_server_answers(display: str) -> str | None:
    """None when an X server accepts a connection at ``display`` as Qt would open it; else why not."""
    why = _x_socket_check(display)
    if why is not None:
        return why
    try:
        import ctypes
        import ctypes.util

        name = ctypes.util.find_library("xcb") or "libxcb.so.1"
        xcb = ctypes.CDLL(name)
    except OSError:
        return None  # the socket answered; libxcb is not there to ask more (Qt will say what it finds)
    xcb.xcb_connect.restype = ctypes.c_void_p
    xcb.xcb_connect.argtypes = (ctypes.c_char_p, ctypes.POINTER(ctypes.c_int))
    xcb.xcb_connection_has_error.argtypes = (ctypes.c_void_p,)
    xcb.xcb_disconnect.argtypes = (ctypes.c_void_p,)
    conn = xcb.xcb_connect(display.encode(), None)
    try:
        err = xcb.xcb_connection_has_error(conn) if conn else -1
    finally:
        if conn:
            xcb.xcb_disconnect(conn)
    if err:
        reasons = {1: "it refused or dropped the connection: not authorised (check XAUTHORITY, or 'xhost') or not "
                      "accepting clients", 5: "the name cannot be parsed", 6: "it has no such screen"}
        why = reasons.get(err, f"xcb error {err}")
        return f"DISPLAY is {display!r} but the X server there cannot be used ({why})"
    return None


def wayland_answers(name: str, environ) -> str | None:
    """None when a Wayland compositor listens at the socket ``name`` (WAYLAND_DISPLAY); else why not."""
    path = name if os.path.isabs(name) else os.path.join(environ.get("XDG_RUNTIME_DIR") or "", name)
    if not os.path.isabs(path):
        return f"WAYLAND_DISPLAY is {name!r} but XDG_RUNTIME_DIR, where its socket would be, is not set"
    try:
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as s:
            s.settimeout(TIMEOUT_S)
            s.connect(path)
    except OSError as exc:
        return f"WAYLAND_DISPLAY is {name!r} but no compositor listens at {path} ({exc.strerror or exc})"
    return None


def display_problem(environ=None, platform: str | None = None) -> str | None:
    """What stops a window from opening (None: nothing, or nothing this check can see).

    Windows and macOS always have a display; a headless Qt platform needs none. Otherwise the
    display Qt would use must answer: an X server at ``DISPLAY`` or a compositor at
    ``WAYLAND_DISPLAY`` (either is enough; Qt falls back from one to the other).
    """
    environ = os.environ if environ is None else environ
    platform = sys.platform if platform is None else platform
    if platform.startswith(("win", "darwin")):
        return None
    qpa = (environ.get("QT_QPA_PLATFORM") or "").split(";")[0].split(":")[0].strip().lower()
    if qpa in HEADLESS_PLATFORMS:
        return None
    x, wl = environ.get("DISPLAY") or "", environ.get("WAYLAND_DISPLAY") or ""
    problems = []
    if wl and qpa in ("", "wayland", "wayland-egl"):
        why = wayland_answers(wl, environ)
        if why is None:
            return None
        problems.append(why)
    if x and qpa in ("", "xcb"):
        why = x_server_answers(x)
        if why is None:
            return None
        problems.append(why)
    return "; ".join(problems) or None
