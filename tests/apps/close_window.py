#!/usr/bin/python3
"""Asks the X window titled TITLE to close, as a window manager's close button does: a
WM_PROTOCOLS client message carrying WM_DELETE_WINDOW (Xvfb runs no window manager).
Usage: close_window.py TITLE [SECONDS]   (waits up to SECONDS, default 20, for the window)
The request is synced, not only flushed: flushing and closing the connection at once lost it in
about a third of the runs here.
"""
import sys
import time

from Xlib import X, display, protocol


def find(window, title):
    if window.get_wm_name() == title:
        return window
    for child in window.query_tree().children:
        found = find(child, title)
        if found:
            return found
    return None


def main():
    title = sys.argv[1]
    deadline = time.time() + (float(sys.argv[2]) if len(sys.argv) > 2 else 20)
    d = display.Display()
    window = None
    while not window and time.time() < deadline:
        window = find(d.screen().root, title)
        if not window:
            time.sleep(0.1)
    if not window:
        sys.exit(f"close_window.py: no window titled '{title}'")
    protocols = d.intern_atom("WM_PROTOCOLS")
    delete = d.intern_atom("WM_DELETE_WINDOW")
    event = protocol.event.ClientMessage(window=window, client_type=protocols,
                                         data=(32, [delete, X.CurrentTime, 0, 0, 0]))
    window.send_event(event, event_mask=X.NoEventMask)
    d.sync()
    d.close()


if __name__ == "__main__":
    main()
