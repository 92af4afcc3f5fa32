#!/usr/bin/python3
"""The controller page's secret in a real browser (Debian's chromium + chromium-driver through
python3-selenium, headless) against a running job (mpirun, a 1x1 OSMesa wall):

- opened at the address dfbwall printed (http://127.0.0.1:PORT/?token=T), the page ends at / (the
  address bar no longer holds the token), loads its style sheet, script and preview, shows the
  status, and a slider change takes effect on the wall; no request after the first carries the
  token (the browser's navigation and resource timing entries) and the page's script cannot
  read the cookie (HttpOnly);
- a page from another origin of the same host (a second HTTP server on another port, so the
  browser sends the cookie along) posting no-cors to /api/stop and /api/settings changes
  nothing: the job runs on with its settings.

    browser_security_test.py LAYOUT       (DFBWALL, MPIEXEC in the environment)
"""
import http.server
import json
import os
import re
import subprocess
import sys
import threading
import time
import urllib.request

from selenium import webdriver
from selenium.webdriver.chrome.options import Options
from selenium.webdriver.chrome.service import Service

layout = sys.argv[1]
dfbwall, mpiexec = os.environ['DFBWALL'], os.environ['MPIEXEC']
mpi_env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT='1', OMPI_ALLOW_RUN_AS_ROOT_CONFIRM='1',
               OMPI_MCA_rmaps_base_oversubscribe='1')


def fail(message):
    print('FAIL:', message, flush=True)
    raise SystemExit(1)


job = subprocess.Popen(
    [mpiexec, '-n', '2', '--oversubscribe', '--bind-to', 'none', dfbwall, '--wall', layout,
     '--offscreen', '--renderer', 'pattern', '--frames', '0', '--control', '127.0.0.1:0',
     '--quiet'],
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


def api(method, path, body=None):
    """The API as a script uses it: the Bearer token."""
    data = None if body is None else json.dumps(body).encode()
    request = urllib.request.Request(base + path, data=data, method=method,
                                     headers={'Authorization': 'Bearer ' + token})
    with urllib.request.urlopen(request, timeout=10) as r:
        return json.loads(r.read())


def wait_for(what, predicate, seconds):
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        value = predicate()
        if value:
            return value
        if job.poll() is not None:
            fail(f'the job ended (exit {job.returncode}) while waiting for {what}:\n' +
                 ''.join(output))
        time.sleep(0.1)
    fail(f'{what}: not within {seconds} s')


class AttackerPage(http.server.BaseHTTPRequestHandler):
    """Another origin on this host: its script posts to the wall's API, as a page the operator
    visits could."""

    def do_GET(self):
        page = f"""<!doctype html><title>attacker</title><script>
Promise.allSettled([
  fetch('{base}/api/settings', {{method: 'POST', mode: 'no-cors', body: '{{"spp": 7}}'}}),
  fetch('{base}/api/settings', {{method: 'POST', mode: 'no-cors', credentials: 'include',
        headers: {{'Content-Type': 'text/plain'}}, body: '{{"exposure": 8}}'}}),
  fetch('{base}/api/stop', {{method: 'POST', mode: 'no-cors', credentials: 'include'}}),
  fetch('{base}/api/stop', {{method: 'POST', mode: 'no-cors', body: '{{}}'}}),
]).then(() => {{ document.title = 'sent'; }});
</script>""".encode()
        self.send_response(200)
        self.send_header('Content-Type', 'text/html')
        self.send_header('Content-Length', str(len(page)))
        self.end_headers()
        self.wfile.write(page)

    def log_message(self, *args):
        pass


driver = None
attacker = None
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
    first = base + '/?token=' + token
    driver.get(first)

    # The page works: its style sheet, its script (the status), the preview.
    wait_for('the status on the page', lambda: driver.execute_script(
        "return /^[0-9]+$/.test(document.getElementById('frame').textContent);"), 20)
    background = driver.execute_script('return getComputedStyle(document.body).backgroundColor;')
    if background != 'rgb(21, 22, 26)':
        fail(f'style.css did not apply (body background {background})')
    wait_for('the preview image', lambda: driver.execute_script(
        "const i = document.getElementById('preview'); return i.complete && i.naturalWidth;"), 20)
    if driver.current_url != base + '/':
        fail(f'the address bar shows {driver.current_url}, expected {base}/')
    if driver.execute_script('return document.cookie;'):
        fail("the page's script can read the cookie")

    # A slider change, through the page's own code, takes effect on the wall.
    driver.execute_script("const s = document.getElementById('spp-per-frame'); s.value = 5;"
                          "s.dispatchEvent(new Event('input'));")
    wait_for('spp 5 from the page', lambda: api('GET', '/api/status')['settings']['spp'] == 5, 20)
    time.sleep(1)  # a few more polls and previews
    urls = driver.execute_script(
        "return performance.getEntriesByType('navigation').concat("
        "performance.getEntriesByType('resource')).map(e => e.name);")
    carrying = [u for u in urls if token in u]
    if carrying or len(urls) < 5:
        fail(f'requests after the first carry the token: {carrying} (of {len(urls)})')
    error = driver.execute_script("const e = document.getElementById('error');"
                                  "return e.hidden ? '' : e.textContent;")
    if error:
        fail('the page shows an error: ' + error)
    print(f'the page at {first.replace(token, "TOKEN")} ended at {driver.current_url}, loaded its '
          f'files and preview, changed spp to 5; none of its {len(urls)} requests after the '
          'first carried the token')

    # Another origin of this host (same site: the cookie goes along) posts to the API.
    status = api('GET', '/api/status')
    attacker = http.server.ThreadingHTTPServer(('127.0.0.1', 0), AttackerPage)
    threading.Thread(target=attacker.serve_forever, daemon=True).start()
    driver.get(f'http://127.0.0.1:{attacker.server_address[1]}/')
    wait_for("the attacker's requests", lambda: driver.title == 'sent', 20)
    time.sleep(1.5)  # a request that got through would be applied by now
    after = api('GET', '/api/status')
    if job.poll() is not None:
        fail(f'the job ended after the attacker page (exit {job.returncode})')
    if after['settings'] != status['settings'] or \
            after['last_request']['id'] != status['last_request']['id']:
        fail(f"the attacker page changed the wall: {status['settings']} -> {after['settings']}")
    print('a page of another origin posting no-cors to /api/stop and /api/settings changed '
          'nothing; the job runs on')

    api('POST', '/api/stop', {})
    try:
        code = job.wait(60)
    except subprocess.TimeoutExpired:
        fail('POST /api/stop did not end the job within 60 s')
    if code != 0:
        fail(f'the job ended with exit {code}:\n' + ''.join(output))
finally:
    if driver:
        driver.quit()
    if attacker:
        attacker.shutdown()
    if job.poll() is None:
        job.terminate()
        try:
            job.wait(10)
        except subprocess.TimeoutExpired:
            job.kill()
            job.wait()
