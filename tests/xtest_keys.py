#!/usr/bin/env python3
"""Presses keys on the X display in $DISPLAY through the XTEST extension (libXtst, by ctypes:
no Python packages needed), for tests/live_smoke.sh. Usage: xtest_keys.py KEY... where KEY is
an X keysym name (e, r, Escape) optionally prefixed with ctrl+ or shift+, e.g. ctrl+e.
The keys go to the window under the pointer (no window manager: focus follows the pointer).
Exit 77 when libX11 or libXtst cannot be loaded or the display cannot be opened."""
import ctypes
import ctypes.util
import sys
import time

# How long a key is held, and the pause after it: the app reads keys once per frame (Dear
# ImGui 1.86 misses a press and release that fall in the same frame).
HOLD_S = 0.2


def main(keys):
    try:
        x11 = ctypes.CDLL(ctypes.util.find_library("X11") or "libX11.so.6")
        xtst = ctypes.CDLL(ctypes.util.find_library("Xtst") or "libXtst.so.6")
    except OSError as e:
        print(f"SKIP: {e}")
        return 77
    x11.XOpenDisplay.restype = ctypes.c_void_p
    x11.XOpenDisplay.argtypes = [ctypes.c_char_p]
    x11.XStringToKeysym.restype = ctypes.c_ulong
    x11.XStringToKeysym.argtypes = [ctypes.c_char_p]
    x11.XKeysymToKeycode.restype = ctypes.c_ubyte
    x11.XKeysymToKeycode.argtypes = [ctypes.c_void_p, ctypes.c_ulong]
    x11.XFlush.argtypes = [ctypes.c_void_p]
    x11.XSync.argtypes = [ctypes.c_void_p, ctypes.c_int]
    x11.XCloseDisplay.argtypes = [ctypes.c_void_p]
    xtst.XTestFakeKeyEvent.argtypes = [ctypes.c_void_p, ctypes.c_uint, ctypes.c_int, ctypes.c_ulong]
    display = x11.XOpenDisplay(None)
    if not display:
        print("SKIP: cannot open the display")
        return 77

    def code(name):
        sym = x11.XStringToKeysym(name.encode())
        if sym == 0:
            raise SystemExit(f"unknown key {name}")
        return x11.XKeysymToKeycode(display, sym)

    modifiers = {"ctrl": "Control_L", "shift": "Shift_L"}
    for key in keys:
        parts = key.split("+")
        held = [code(modifiers[p]) for p in parts[:-1]]
        for c in held:
            xtst.XTestFakeKeyEvent(display, c, 1, 0)
        k = code(parts[-1])
        xtst.XTestFakeKeyEvent(display, k, 1, 0)
        x11.XSync(display, 0)
        time.sleep(HOLD_S)
        xtst.XTestFakeKeyEvent(display, k, 0, 0)
        for c in reversed(held):
            xtst.XTestFakeKeyEvent(display, c, 0, 0)
        x11.XSync(display, 0)
        time.sleep(HOLD_S)
    x11.XCloseDisplay(display)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
