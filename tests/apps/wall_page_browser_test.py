#!/usr/bin/python3
"""The wall's page (serve --control) in a real browser: headless Chromium (Debian's chromium +
chromium-driver, through python3-selenium) on a 2x2 OSMesa service wall with two pattern jobs in
overlapping windows.

    wall_page_browser_test.py LAYOUT      (DFBWALL, COMPARE, MPIEXEC in the environment)

 - the page draws the four displays and both windows to scale, the newest on top, job a's window
   linking its job's page and job b's (which has none) linking nothing;
 - a click on job a's window raises it: the wall's API says so, and the page marks it on top;
 - a drag of job b's title bar asks the wall to move it: the wall answers 501 (not done yet), the
   page says so in words and puts the window back where the wall has it;
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
from wall_manager_test import DFBWALL, MPI, SCALE, WINDOW_A, WINDOW_B, Http, Test  # noqa: E402


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


def run(t):
    port = 20000 + os.getpid() % 20000
    control = port + 1
    token_file = os.path.join(t.work, "wall-control-token")
    serve = t.start("serve", MPI + [
        "-np", "4", DFBWALL, "serve", "--wall", t.layout, "--listen", "127.0.0.1:%d" % port,
        "--offscreen", "--timeout", str(8 * SCALE), "--max-jobs", "2", "--background", "#000000",
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
    job = ["--renderer", "pattern", "--frames", "100000", "--quiet", "--timeout", "30"]
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

    # A drag of window 2's title bar: 501 from the wall, said in words; the window goes back.
    bar = windows["2"].find_element(By.CSS_SELECTOR, ".bar")
    ActionChains(driver).move_to_element_with_offset(bar, -20, 0).click_and_hold() \
        .move_by_offset(40, 0).pause(0.2).move_by_offset(40, 30).release().perform()
    t.wait_for("the page to say moving is not done",
               lambda: "not done yet" in driver.find_element(By.ID, "error").text, 5)
    t.wait_for("window 2 back in its place", lambda: placed(driver, windows["2"], WINDOW_B), 5)
    if {w["id"]: w["z"] for w in api.get("/api/windows")[2]} != {"1": 1, "2": 0}:
        t.fail("the drag raised window 2 (a drag is not a click)")
    print("a drag was answered 501: '%s'" % driver.find_element(By.ID, "error").text)

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
    print("PASS: the wall's page drew the wall and its windows, raised one by a click, said a "
          "move is not done yet, and closed a job")


if __name__ == "__main__":
    main()
