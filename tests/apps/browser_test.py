#!/usr/bin/python3
"""A real browser on a real wall: headless Chromium (Debian's chromium +
chromium-driver, driven through python3-selenium) opens the controller page of a running dfbwall
job (mpirun, OSMesa wall, --frames 0 --control), sees the preview image load, drags on it, and
the job's camera changes: /api/status reports another camera, and a capture after the drag
differs from one before. Then the page at a phone's size, and POST /api/stop ends the job with
exit 0.

    browser_test.py LAYOUT RENDER_RANKS      (DFBWALL, COMPARE, MPIEXEC in the environment)

Debian's Python is used on purpose (/usr/bin/python3): it sees Debian's selenium.
"""
import json
import os
import re
import subprocess
import sys
import tempfile
import threading
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service
from selenium.webdriver.common.action_chains import ActionChains
from selenium.webdriver.common.by import By
from selenium.webdriver.support.ui import WebDriverWait

layout, renders = sys.argv[1], int(sys.argv[2])
dfbwall, mpiexec = os.environ['DFBWALL'], os.environ['MPIEXEC']
work = tempfile.mkdtemp(prefix='dfbwall-browser-')
captures = os.path.join(work, 'cap')


def fail(message):
    print('FAIL:', message, flush=True)
    raise SystemExit(1)


mpi_env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT='1', OMPI_ALLOW_RUN_AS_ROOT_CONFIRM='1',
               OMPI_MCA_rmaps_base_oversubscribe='1')
# Wall processes of the layout, as compare_captures --info reads them ("W WIDTHxHEIGHT").
walls = int(subprocess.run([os.environ['COMPARE'], '--info', layout], capture_output=True,
                           text=True, check=True).stdout.split()[0])
job = subprocess.Popen(
    [mpiexec, '-n', str(renders + walls), '--oversubscribe', '--bind-to', 'none', dfbwall,
     '--wall', layout, '--offscreen', '--renderer', 'primary', '--scene', 'builtin:cornell',
     '--frames', '0', '--control', '127.0.0.1:0', '--capture', captures, '--quiet'],
    stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=mpi_env)
output = []
address = threading.Event()
base = token = None


def read_output():
    global base, token
    for line in job.stdout:
        output.append(line)
        m = re.search(r'control API on (http://[0-9.]+:\d+)/\?token=(\S+)', line)
        if m and not base:
            base, token = m.groups()
            address.set()


threading.Thread(target=read_output, daemon=True).start()
driver = None


def api(method, path, body=None):
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(base + path, data=data, method=method,
                                     headers={'Content-Type': 'application/json',
                                              'Authorization': 'Bearer ' + token})
    with urllib.request.urlopen(request, timeout=10) as r:
        payload = r.read()
        return json.loads(payload) if r.headers.get_content_type() == 'application/json' else payload


def wait_for(what, predicate, seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        if job.poll() is not None:
            fail(f'the job ended (exit {job.returncode}) while waiting for {what}:\n' + ''.join(output))
        time.sleep(0.1)
    fail(f'{what}: not within {seconds} s')


def first_display_folder():
    """The first display's capture folder (captures/<display>/), once it exists."""
    if not os.path.isdir(captures):
        return None
    folders = sorted(f for f in os.listdir(captures) if os.path.isdir(os.path.join(captures, f)))
    return os.path.join(captures, folders[0]) if folders else None


def capture():
    """Asks for a capture and returns the new PNG of the first display, as bytes."""
    folder = first_display_folder()
    before = set(os.listdir(folder)) if folder else set()
    api('POST', '/api/capture', {})

    def new_file():
        d = first_display_folder()
        if not d:
            return None
        # Captures are written to a temporary name and renamed: a .png name is a whole file.
        fresh = sorted(f for f in set(os.listdir(d)) - before if f.endswith('.png'))
        return os.path.join(d, fresh[-1]) if fresh else None
    path = wait_for('a capture', new_file, 30)
    with open(path, 'rb') as f:
        return path, f.read()


try:
    if not address.wait(90):
        fail('dfbwall did not print the control address:\n' + ''.join(output))
    wait_for('the first frame', lambda: api('GET', '/api/status')['frame'] >= 2, 60)

    options = Options()
    options.binary_location = '/usr/bin/chromium'
    for flag in ('--headless=new', '--no-sandbox', '--disable-gpu', '--disable-dev-shm-usage',
                 '--window-size=1280,900'):
        options.add_argument(flag)
    driver = webdriver.Chrome(service=Service('/usr/bin/chromedriver'), options=options)
    driver.set_page_load_timeout(30)
    driver.get(base + '/?token=' + token)  # the address dfbwall printed

    # The preview loads, at the size the layout says.
    layout_info = api('GET', '/api/layout')
    width = wait_for('the preview image', lambda: driver.execute_script(
        "const i = document.getElementById('preview'); return i.complete && i.naturalWidth;"), 30)
    if width != layout_info['preview']['size'][0]:
        fail(f"preview is {width} wide, /api/layout says {layout_info['preview']['size']}")
    names = [d['name'] for d in layout_info['displays']]
    wait_for('the display outlines', lambda: len(driver.find_elements(By.CSS_SELECTOR, '.display'))
             == len(names), 10)
    wait_for('per-display presented frames', lambda: len(driver.find_elements(
        By.CSS_SELECTOR, '#displays tbody tr')) == len(names), 10)
    print(f'preview {width} px wide loaded; {len(names)} displays outlined: {", ".join(names)}')

    camera_before = api('GET', '/api/status')['camera']
    first_path, first = capture()

    stage = driver.find_element(By.ID, 'stage')
    ActionChains(driver).move_to_element(stage).click_and_hold().move_by_offset(80, 0) \
        .pause(0.2).move_by_offset(80, 10).release().perform()
    camera_after = wait_for('a new camera after the drag', lambda: (
        lambda c: c if c != camera_before else None)(api('GET', '/api/status')['camera']), 20)
    print(f"camera moved: {camera_before['position']} -> {camera_after['position']}")

    # A capture of a frame rendered with the new camera differs from the one before.
    time.sleep(1)
    second_path, second = capture()
    if second == first:
        fail(f'{second_path} equals {first_path}: the displays did not change after the drag')
    print(f'captures differ: {os.path.basename(first_path)} vs {os.path.basename(second_path)}')

    error = driver.execute_script("const e = document.getElementById('error');"
                                  "return e.hidden ? '' : e.textContent;")
    if error:
        fail('the page shows an error: ' + error)

    # A phone-sized screen: the preview fits, the controls are reachable below it.
    driver.set_window_size(390, 844)
    fits = wait_for('the preview at phone size', lambda: driver.execute_script(
        "const r = document.getElementById('preview').getBoundingClientRect();"
        "return r.width > 0 && r.right <= window.innerWidth + 1;"), 10)
    stop_button = driver.find_element(By.ID, 'stop')
    if not (fits and stop_button.is_displayed()):
        fail('at 390 px the preview overflows or the stop button is gone')
    print('phone size: the preview fits the width, the controls follow')

    api('POST', '/api/stop', {})
    try:
        code = job.wait(60)
    except subprocess.TimeoutExpired:
        fail('POST /api/stop did not end the job within 60 s')
    if code != 0:
        fail(f'the job ended with exit {code}:\n' + ''.join(output))
    print('POST /api/stop: the job ended with exit 0')
finally:
    if driver:
        driver.quit()
    if job.poll() is None:  # mpirun forwards SIGTERM to its ranks; SIGKILL only if it hangs
        job.terminate()
        try:
            job.wait(10)
        except subprocess.TimeoutExpired:
            job.kill()
            job.wait()
    subprocess.run(['rm', '-rf', work])
