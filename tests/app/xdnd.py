"""A minimal XDND drag source for the window tests (xdotool cannot drop files).

Speaks the source side of the X Drag-and-Drop protocol (version 5) to the
editor's glfw window through libX11 (ctypes): XdndEnter offering
``text/uri-list``, XdndPosition over a point of the window, XdndDrop once
the target answers XdndStatus, then the ``XdndSelection`` conversion glfw
asks for (the file URIs) and the target's XdndFinished.  Enough to deliver
a real drop to glfw's drop callback under Xvfb.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import time
import urllib.parse
from pathlib import Path

_CLIENT_MESSAGE, _SELECTION_REQUEST, _SELECTION_NOTIFY = 33, 30, 31
_PROP_MODE_REPLACE = 0


class _ClientMessage(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("serial", ctypes.c_ulong), ("send_event", ctypes.c_int),
                ("display", ctypes.c_void_p), ("window", ctypes.c_ulong), ("message_type", ctypes.c_ulong),
                ("format", ctypes.c_int), ("l", ctypes.c_long * 5)]


class _SelectionRequest(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("serial", ctypes.c_ulong), ("send_event", ctypes.c_int),
                ("display", ctypes.c_void_p), ("owner", ctypes.c_ulong), ("requestor", ctypes.c_ulong),
                ("selection", ctypes.c_ulong), ("target", ctypes.c_ulong), ("property", ctypes.c_ulong),
                ("time", ctypes.c_ulong)]


class _Selection(ctypes.Structure):
    _fields_ = [("type", ctypes.c_int), ("serial", ctypes.c_ulong), ("send_event", ctypes.c_int),
                ("display", ctypes.c_void_p), ("requestor", ctypes.c_ulong), ("selection", ctypes.c_ulong),
                ("target", ctypes.c_ulong), ("property", ctypes.c_ulong), ("time", ctypes.c_ulong)]


class _XEvent(ctypes.Union):
    _fields_ = [("type", ctypes.c_int), ("xclient", _ClientMessage), ("xselectionrequest", _SelectionRequest),
                ("xselection", _Selection), ("pad", ctypes.c_long * 24)]


def _x11():
    x = ctypes.CDLL(ctypes.util.find_library("X11") or "libX11.so.6")
    x.XOpenDisplay.restype = ctypes.c_void_p
    x.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x.XInternAtom.restype = ctypes.c_ulong
    x.XInternAtom.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_int]
    x.XDefaultRootWindow.restype = ctypes.c_ulong
    x.XDefaultRootWindow.argtypes = [ctypes.c_void_p]
    x.XCreateSimpleWindow.restype = ctypes.c_ulong
    x.XCreateSimpleWindow.argtypes = [ctypes.c_void_p, ctypes.c_ulong] + [ctypes.c_int] * 2 + \
        [ctypes.c_uint] * 3 + [ctypes.c_ulong] * 2
    x.XSetSelectionOwner.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong]
    x.XSendEvent.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_int, ctypes.c_long, ctypes.c_void_p]
    x.XChangeProperty.argtypes = [ctypes.c_void_p, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_ulong, ctypes.c_int,
                                  ctypes.c_int, ctypes.c_char_p, ctypes.c_int]
    x.XPending.argtypes = [ctypes.c_void_p]
    x.XNextEvent.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
    x.XFlush.argtypes = [ctypes.c_void_p]
    x.XDestroyWindow.argtypes = [ctypes.c_void_p, ctypes.c_ulong]
    x.XCloseDisplay.argtypes = [ctypes.c_void_p]
    return x


def drop_files(display: str, target: int, paths, x: int, y: int, timeout: float = 10.0) -> None:
    """Drop ``paths`` on X window ``target`` at root pixel (x, y) on ``display``.

    Raises AssertionError when the target does not take part in the protocol
    in time."""
    X = _x11()
    dpy = X.XOpenDisplay(display.encode())
    assert dpy, f"cannot open display {display}"
    atom = lambda name: X.XInternAtom(dpy, name.encode(), 0)  # noqa: E731
    a = {n: atom(n) for n in ("XdndEnter", "XdndPosition", "XdndStatus", "XdndDrop", "XdndFinished",
                              "XdndSelection", "XdndActionCopy", "text/uri-list")}
    src = X.XCreateSimpleWindow(dpy, X.XDefaultRootWindow(dpy), 0, 0, 1, 1, 0, 0, 0)
    uris = "".join("file://" + urllib.parse.quote(str(Path(p).resolve())) + "\r\n" for p in paths).encode()

    def send(kind, l1=0, l2=0, l3=0, l4=0):
        ev = _XEvent()
        ev.xclient.type = _CLIENT_MESSAGE
        ev.xclient.window = target
        ev.xclient.message_type = a[kind]
        ev.xclient.format = 32
        ev.xclient.l[:] = [src, l1, l2, l3, l4]
        X.XSendEvent(dpy, target, 0, 0, ctypes.byref(ev))
        X.XFlush(dpy)

    def wait_for(pred, what):
        t0 = time.time()
        ev = _XEvent()
        while time.time() - t0 < timeout:
            while X.XPending(dpy):
                X.XNextEvent(dpy, ctypes.byref(ev))
                if ev.type == _SELECTION_REQUEST:
                    _answer(X, dpy, ev.xselectionrequest, uris, a["text/uri-list"])
                if pred(ev):
                    return
            time.sleep(0.01)
        raise AssertionError(f"XDND: no {what} from window {target:#x}")

    try:
        X.XSetSelectionOwner(dpy, a["XdndSelection"], src, 0)
        send("XdndEnter", 5 << 24, a["text/uri-list"])
        send("XdndPosition", 0, (int(x) << 16) | int(y), 0, a["XdndActionCopy"])
        wait_for(lambda e: e.type == _CLIENT_MESSAGE and e.xclient.message_type == a["XdndStatus"], "XdndStatus")
        send("XdndDrop", 0, 0)
        wait_for(lambda e: e.type == _CLIENT_MESSAGE and e.xclient.message_type == a["XdndFinished"],
                 "XdndFinished")
    finally:
        X.XDestroyWindow(dpy, src)
        X.XCloseDisplay(dpy)


def _answer(X, dpy, req: _SelectionRequest, data: bytes, uri_list: int) -> None:
    """Hand the URI list to the requestor of the XdndSelection."""
    ok = req.target == uri_list
    if ok:
        X.XChangeProperty(dpy, req.requestor, req.property, req.target, 8, _PROP_MODE_REPLACE, data, len(data))
    ev = _XEvent()
    ev.xselection.type = _SELECTION_NOTIFY
    ev.xselection.requestor = req.requestor
    ev.xselection.selection = req.selection
    ev.xselection.target = req.target
    ev.xselection.property = req.property if ok else 0
    ev.xselection.time = req.time
    X.XSendEvent(dpy, req.requestor, 0, 0, ctypes.byref(ev))
    X.XFlush(dpy)
