#!/usr/bin/python3
"""The wall's page (serve --control) in a real browser: headless Chromium (Debian's chromium +
chromium-driver, through python3-selenium) on a 2x2 OSMesa service wall (`--capture`: what each
display shows) with two jobs of the primary renderer (the same picture every frame) in
overlapping windows.

    wall_page_browser_test.py LAYOUT      (DFBWALL, COMPARE, MPIEXEC in the environment)

 - the page draws the four displays and both windows to scale, the newest on top, job a's window
   linking its job's page and job b's (which has none) linking nothing;
 - each window shows its live thumbnail: an <img> per window, loaded from the wall's API (its
   cookie), of the window's thumbnail size and not blank, reloaded at least once a second;
 - a click on job a's window raises it: the wall's API says so, and the page marks it on top;
 - a drag of job a's title bar (a job with its own page and preview) moves its window: the
   wall's API lists it at the new place and the page draws it there;
 - a drag of job b's title bar moves its window: the wall's API lists it at the new place, the
   page draws it there, and the wall's captures show it there (under job a's, raised before: a
   moved window keeps its place in the stack), equal to the composite of both one-process
   renders; a click raises it and a drag of its corner resizes it: the same at the new size
   (job b re-renders at that size), over job a's;
 - job b's close button ends job b (exit non-zero, told why) and its window leaves the page.
Debian's Python is used on purpose (/usr/bin/python3): it sees Debian's selenium.
"""
import os
import re
import signal
import subprocess
import sys
import time

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from wall_manager_test import (DFBWALL, ENV, MPI, SCALE, WINDOW_A, WINDOW_B, Http, Test,  # noqa: E402
                               composite, forget_captures)


DRIVERS = []  # quit however the test ends


def main():
    t = Test(sys.argv[1])
    try:
        run(t)
    except SystemExit:
        raise
    except BaseException as e:  # noqa: B902 (a Python or browser error fails with the logs)
        t.fail("%s: %s" % (type(e).__name__, e))
    finally:
        for driver in DRIVERS:
            driver.quit()
    t.cleanup()


def box_rect(driver, element):
    """An element's rectangle on the page: [x, y, w, h]."""
    r = driver.execute_script("const r = arguments[0].getBoundingClientRect();"
                              "return [r.left, r.top, r.width, r.height];", element)
    return [round(v, 1) for v in r]


def placed(driver, element, window):
    """The element is drawn at the canvas rectangle "X,Y,W,H" on the wall as drawn now."""
    wall = box_rect(driver, driver.find_element(By.ID, "wall"))
    scale = wall[2] / 412
    x, y, w, h = map(int, window.split(","))
    expected = [wall[0] + x * scale, wall[1] + y * scale, w * scale, h * scale]
    return all(abs(a - b) <= 1.5 for a, b in zip(box_rect(driver, element), expected))


def thumbnail_shown(driver, box):
    """The window's thumbnail <img> once it loaded: its natural size, the distinct colours of
    its pixels (read back through a canvas: a same-origin image), whether it is shown, its
    address; None before."""
    return driver.execute_script("""
        const img = arguments[0].querySelector('img.thumb');
        if (!img || !img.complete || img.naturalWidth === 0) return null;
        const c = document.createElement('canvas');
        c.width = img.naturalWidth;
        c.height = img.naturalHeight;
        const g = c.getContext('2d');
        g.drawImage(img, 0, 0);
        const d = g.getImageData(0, 0, c.width, c.height).data;
        const colors = new Set();
        for (let i = 0; i < d.length; i += 4)
          colors.add((d[i] << 16) | (d[i + 1] << 8) | d[i + 2]);
        const r = img.getBoundingClientRect();
        return {size: [img.naturalWidth, img.naturalHeight], colors: colors.size,
                visible: !img.hidden && r.width > 0 && r.height > 0,
                src: img.getAttribute('src')};""", box)


def as_rect(window):
    x, y, w, h = map(int, window.split(","))
    return {"x": x, "y": y, "w": w, "h": h}


def text(rect):
    return "%d,%d,%d,%d" % (rect["x"], rect["y"], rect["w"], rect["h"])


def render(t, size):
    """The one-process render of the jobs' picture at SIZE ("WxH"); its PNG's path."""
    path = os.path.join(t.work, "ref-%s.png" % size)
    if not os.path.exists(path):
        subprocess.check_call(MPI + ["-np", "1", DFBWALL, "--renderer", "primary", "--size", size,
                                     "--frames", "1", "--quiet", "--image", path], env=ENV)
    return path


def run(t):
    port = 20000 + os.getpid() % 20000
    control = port + 1
    token_file = os.path.join(t.work, "wall-control-token")
    captures = os.path.join(t.work, "wall")
    # The one-process renders the wall's captures are compared with, while the host is idle:
    # both windows, and window 2 after its resize (20 x 10 canvas pixels larger, below).
    ref_a, ref_b, ref_resized = render(t, "250x170"), render(t, "200x150"), render(t, "220x160")
    serve = t.start("serve", MPI + [
        "-np", "4", DFBWALL, "serve", "--wall", t.layout, "--listen", "127.0.0.1:%d" % port,
        "--offscreen", "--timeout", str(8 * SCALE), "--max-jobs", "2", "--background", "#000000",
        "--capture", captures, "--capture-every", "4",
        "--control", "127.0.0.1:%d" % control, "--control-token-file", token_file])
    t.wait_for("serve to start", lambda: "window manager:" in t.log("serve"), 20)
    api = Http(control, open(token_file).read().strip())
    # The browser first: it starts slowly on a host the jobs keep busy.
    options = Options()
    options.binary_location = "/usr/bin/chromium"
    for flag in ("--headless=new", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
                 "--window-size=1280,900"):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service("/usr/bin/chromedriver"), options=options)
    DRIVERS.append(driver)
    driver.set_page_load_timeout(30)
    job = ["--renderer", "primary", "--frames", "100000", "--quiet", "--timeout", "30"]
    t.start("a", MPI + ["-np", "1", DFBWALL, "--connect", "127.0.0.1:%d" % port, "--window",
                        WINDOW_A, "--control", "127.0.0.1:0", "--control-token-file",
                        os.path.join(t.work, "job-token")] + job)
    t.wait_for("job a running", lambda: [w["state"] for w in api.get("/api/windows")[2]] ==
               ["running"], 20)
    t.start("b", MPI + ["-np", "1", DFBWALL, "--connect", "127.0.0.1:%d" % port, "--window",
                        WINDOW_B] + job)
    t.wait_for("job b running", lambda: [w["state"] for w in api.get("/api/windows")[2]] ==
               ["running", "running"], 20)
    page_a = re.search(r"control API on (http://127\.0\.0\.1:\d+/)", t.log("a")).group(1)

    driver.get("http://127.0.0.1:%d/?token=%s" % (control, api.token))  # what serve printed
    if "token" in driver.current_url:
        t.fail("the token stayed in the address bar: " + driver.current_url)

    # The displays and both windows, to scale.
    t.wait_for("the displays", lambda: len(driver.find_elements(By.CSS_SELECTOR, ".display")) == 4,
               10)
    t.wait_for("both windows", lambda: len(driver.find_elements(By.CSS_SELECTOR, ".window")) == 2,
               10)
    wall = box_rect(driver, driver.find_element(By.ID, "wall"))
    if abs(wall[3] - 310 * wall[2] / 412) > 1.5:
        t.fail("the wall is drawn %r, not 412x310 to scale" % wall)
    windows = {e.get_attribute("data-id"): e for e in
               driver.find_elements(By.CSS_SELECTOR, ".window")}
    for wid, window in [("1", WINDOW_A), ("2", WINDOW_B)]:
        if not placed(driver, windows[wid], window):
            t.fail("window %s drawn at %r on a wall at %r, not at %s" %
                   (wid, box_rect(driver, windows[wid]), wall, window))
    if "top" not in windows["2"].get_attribute("class") or \
            "top" in windows["1"].get_attribute("class"):
        t.fail("the newest window (2) is not marked on top")
    link_a = windows["1"].find_element(By.CSS_SELECTOR, "a.page")
    if not link_a.is_displayed() or link_a.get_attribute("href") != page_a:
        t.fail("window 1 links %r, job a's page is %s" % (link_a.get_attribute("href"), page_a))
    if windows["2"].find_element(By.CSS_SELECTOR, "a.page").is_displayed():
        t.fail("window 2 links a page its job does not have")
    print("the page draws 4 displays and 2 windows to scale; window 1 links %s" % page_a)

    # Each window's live thumbnail: loaded (the cookie authenticates it), the thumbnail's size
    # (320 on the long side at most: the windows' own sizes here), not blank, and refreshed.
    colors = []
    for wid, window in [("1", WINDOW_A), ("2", WINDOW_B)]:
        size = [int(v) for v in window.split(",")[2:]]
        shown = t.wait_for("window %s's thumbnail on the page" % wid,
                           lambda: thumbnail_shown(driver, windows[wid]), 15)
        if shown["size"] != size or shown["colors"] < 16 or not shown["visible"]:
            t.fail("window %s's thumbnail on the page: %r (its window is %s)" %
                   (wid, shown, window))
        first = shown["src"]
        later = t.wait_for("window %s's thumbnail to be loaded again" % wid, lambda: (
            lambda now: now if now and now["src"] != first else None)(
                thumbnail_shown(driver, windows[wid])), 5)
        if later["size"] != size or later["colors"] < 16:
            t.fail("window %s's thumbnail loaded again: %r" % (wid, later))
        colors.append(later["colors"])
    print("each window shows its thumbnail (%d and %d colours), loaded again within 5 s" %
          tuple(colors))

    # A click on window 1 (where window 2 does not cover it) raises it.
    r1 = box_rect(driver, windows["1"])
    ActionChains(driver).move_to_element_with_offset(
        windows["1"], int(r1[2] / 2 - 10), int(r1[3] / 2 - 10)).click().perform()
    t.wait_for("window 1 on top (API)", lambda: {w["id"]: w["z"] for w in
                                                 api.get("/api/windows")[2]} == {"1": 1, "2": 0}, 5)
    t.wait_for("window 1 on top (page)",
               lambda: "top" in windows["1"].get_attribute("class") and
               int(windows["1"].value_of_css_property("z-index")) >
               int(windows["2"].value_of_css_property("z-index")), 5)
    print("a click raised window 1")

    # Window 1 (on top now) is job a's, which has its own page and preview: a drag moves it.
    rect_of = lambda wid: {w["id"]: w["rect"] for w in api.get("/api/windows")[2]}.get(wid)
    bar = windows["1"].find_element(By.CSS_SELECTOR, ".bar")
    ActionChains(driver).move_to_element_with_offset(bar, -20, 0).click_and_hold() \
        .move_by_offset(20, 0).pause(0.2).move_by_offset(20, 10).release().perform()
    moved_a = t.wait_for("window 1 moved (API)", lambda: rect_of("1") if
                         rect_of("1") != as_rect(WINDOW_A) else None, 10)
    if (moved_a["w"], moved_a["h"]) != (250, 170) or moved_a["x"] <= 90:
        t.fail("the drag moved window 1 to %r (from %s)" % (moved_a, WINDOW_A))
    a_text = text(moved_a)
    t.wait_for("window 1 drawn at %s" % a_text, lambda: placed(driver, windows["1"], a_text), 5)
    print("a drag moved window 1 (a job with its own page) to %s" % a_text)

    # A drag of window 2's title bar moves it: the API, the page and the wall's captures.
    forget_captures(captures)
    bar = windows["2"].find_element(By.CSS_SELECTOR, ".bar")
    ActionChains(driver).move_to_element_with_offset(bar, -20, 0).click_and_hold() \
        .move_by_offset(40, 0).pause(0.2).move_by_offset(40, 30).release().perform()
    moved = t.wait_for("window 2 moved (API)", lambda: rect_of("2") if
                       rect_of("2") != as_rect(WINDOW_B) else None, 10)
    if (moved["w"], moved["h"]) != (200, 150) or moved["x"] <= 20 or moved["y"] <= 20:
        t.fail("the drag moved window 2 to %r (from %s, by +80,+30 page pixels)" %
               (moved, WINDOW_B))
    moved_text = text(moved)
    t.wait_for("window 2 drawn at %s" % moved_text,
               lambda: placed(driver, windows["2"], moved_text), 5)
    if not driver.find_element(By.ID, "error").text == "":
        t.fail("the page shows an error after a move: " + driver.find_element(By.ID, "error").text)
    # Window 1, raised, stays on top: a moved window keeps its place in the stack.
    t.wait_for("the wall's captures of window 2 at %s under window 1" % moved_text,
               lambda: composite(t, moved_text + "+" + a_text, ref_b + "+" + ref_a, captures), 15)
    print("a drag moved window 2 to %s: listed, drawn and shown on the wall" % moved_text)

    # A drag of its corner resizes it (raised first by a click on its title bar: window 1 covers
    # the corner).
    windows["2"].find_element(By.CSS_SELECTOR, ".title").click()
    t.wait_for("window 2 on top (API)", lambda: {w["id"]: w["z"] for w in
                                                 api.get("/api/windows")[2]} == {"1": 0, "2": 1}, 5)
    t.wait_for("window 2 on top (page)", lambda: "top" in windows["2"].get_attribute("class"), 5)
    forget_captures(captures)
    corner = windows["2"].find_element(By.CSS_SELECTOR, ".resize")
    # Page pixels for 20 x 10 canvas pixels (the page rounds to canvas pixels; drawn larger than
    # the canvas, one page pixel is less than one canvas pixel, so this lands exactly).
    per_pixel = box_rect(driver, driver.find_element(By.ID, "wall"))[2] / 412
    dx, dy = round(20 * per_pixel), round(10 * per_pixel)
    ActionChains(driver).move_to_element(corner).click_and_hold() \
        .move_by_offset(dx // 2, 0).pause(0.2).move_by_offset(dx - dx // 2, dy).release().perform()
    resized = t.wait_for("window 2 resized (API)", lambda: rect_of("2") if
                         rect_of("2") != moved else None, 10)
    if (resized["x"], resized["y"]) != (moved["x"], moved["y"]) or \
            resized["w"] <= moved["w"] or resized["h"] <= moved["h"]:
        t.fail("the corner's drag made window 2 %r (from %r)" % (resized, moved))
    resized_text = text(resized)
    t.wait_for("window 2 drawn at %s" % resized_text,
               lambda: placed(driver, windows["2"], resized_text), 5)
    if (resized["w"], resized["h"]) != (220, 160):  # a page drawn smaller than the canvas
        ref_resized = render(t, "%dx%d" % (resized["w"], resized["h"]))
    t.wait_for("the wall's captures of window 2 at %s" % resized_text, lambda: composite(
        t, a_text + "+" + resized_text, ref_a + "+" + ref_resized, captures), 15)
    print("a drag of its corner resized window 2 to %s: listed, drawn and shown on the wall"
          % resized_text)

    # Close window 2: job b ends, told why; its window leaves the page.
    windows["2"].find_element(By.CSS_SELECTOR, "button.close").click()
    code = t.procs["b"].wait(timeout=20 * SCALE)
    if code == 0 or "closed from the wall's control page" not in t.log("b"):
        t.fail("job b: exit %d after its close button" % code)
    t.wait_for("window 2 to leave the page", lambda: [
        e.get_attribute("data-id") for e in driver.find_elements(By.CSS_SELECTOR, ".window")] ==
        ["1"], 10)
    print("the close button ended job b and its window left the page")

    serve.send_signal(signal.SIGUSR1)
    if serve.wait(timeout=20 * SCALE) != 0:
        t.fail("serve exited non-zero after SIGUSR1")
    t.procs["a"].wait(timeout=20 * SCALE)
    print("PASS: the wall's page drew the wall and its windows, raised one by a click, moved a "
          "job with its own page and another by a drag, resized one by its corner (the wall's "
          "captures show both), and closed a job")


if __name__ == "__main__":
    main()
