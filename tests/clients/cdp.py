"""cdp.py - drives headless Chromium through the DevTools protocol over a pipe
(--remote-debugging-pipe: NUL-separated JSON on file descriptors 3 and 4), standard library only.
Used by test_dashboard.sh.

    with Browser() as b:
        page = b.new_page("http://127.0.0.1:8080/")
        page.wait_for("document.querySelectorAll('tr').length > 1", timeout=10)
        png = page.screenshot_of("#viewer canvas")
        busy = count_non_background(png)
"""

import base64
import json
import os
import select
import shutil
import struct
import subprocess
import tempfile
import time
import zlib


class CdpError(Exception):
    pass


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        p = shutil.which(name)
        if p:
            return p
    return None


class Browser:
    def __init__(self, binary=None, width=1280, height=1800):
        self.width, self.height = width, height
        self.binary = binary or find_chromium()
        if not self.binary:
            raise CdpError("no chromium found (Debian: apt-get install chromium)")
        self.profile = tempfile.mkdtemp(prefix="polydem-chromium-")
        to_chrome_r, self._w = os.pipe()
        self._r, from_chrome_w = os.pipe()

        def child_fds():
            os.dup2(to_chrome_r, 3)
            os.dup2(from_chrome_w, 4)

        args = [self.binary, "--headless=new", "--no-sandbox", "--disable-gpu-sandbox",
                "--use-angle=swiftshader", "--enable-unsafe-swiftshader", "--ignore-gpu-blocklist",
                "--no-first-run", "--no-default-browser-check", "--disable-extensions",
                "--disable-background-networking", "--disable-dev-shm-usage", "--mute-audio",
                "--remote-debugging-pipe", "--user-data-dir=" + self.profile,
                "--window-size=%d,%d" % (width, height), "about:blank"]
        self.proc = subprocess.Popen(args, pass_fds=(3, 4), preexec_fn=child_fds,
                                     stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                                     stderr=subprocess.DEVNULL)
        os.close(to_chrome_r)
        os.close(from_chrome_w)
        self._buf = b""
        self._id = 0
        self.events = []  # (sessionId, method, params) not yet consumed
        self.call("Browser.getVersion", timeout=30)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()

    def close(self):
        if self.proc.poll() is None:
            try:
                self.call("Browser.close", timeout=5)
            except (CdpError, OSError):
                pass
            try:
                self.proc.wait(timeout=5)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()
        for fd in (self._r, self._w):
            try:
                os.close(fd)
            except OSError:
                pass
        shutil.rmtree(self.profile, ignore_errors=True)

    def _read_message(self, deadline):
        while b"\0" not in self._buf:
            left = deadline - time.monotonic()
            if left <= 0:
                raise CdpError("no answer from chromium in time")
            ready, _, _ = select.select([self._r], [], [], left)
            if ready:
                chunk = os.read(self._r, 1 << 20)
                if not chunk:
                    raise CdpError("chromium closed the DevTools pipe (exit %s)" % self.proc.poll())
                self._buf += chunk
        msg, self._buf = self._buf.split(b"\0", 1)
        return json.loads(msg)

    def call(self, method, params=None, session=None, timeout=20):
        self._id += 1
        my = self._id
        m = {"id": my, "method": method, "params": params or {}}
        if session:
            m["sessionId"] = session
        os.write(self._w, json.dumps(m).encode() + b"\0")
        deadline = time.monotonic() + timeout
        while True:
            d = self._read_message(deadline)
            if d.get("id") == my:
                if "error" in d:
                    raise CdpError("%s: %s" % (method, d["error"].get("message")))
                return d.get("result", {})
            if "method" in d:
                self.events.append((d.get("sessionId"), d["method"], d.get("params", {})))

    def pump(self, seconds):
        """Reads events for a while (console messages, exceptions)."""
        deadline = time.monotonic() + seconds
        try:
            while True:
                d = self._read_message(deadline)
                if "method" in d:
                    self.events.append((d.get("sessionId"), d["method"], d.get("params", {})))
        except CdpError:
            pass

    def new_page(self, url):
        target = self.call("Target.createTarget", {"url": "about:blank"})["targetId"]
        session = self.call("Target.attachToTarget", {"targetId": target, "flatten": True})["sessionId"]
        page = Page(self, session)
        # A viewport that holds the whole page: screenshots need no scrolling, and the layout
        # does not change between measuring an element and photographing it.
        page.call("Emulation.setDeviceMetricsOverride", {"width": self.width, "height": self.height,
                                                          "deviceScaleFactor": 1, "mobile": False})
        page.call("Page.enable")
        page.call("Runtime.enable")
        page.goto(url)
        return page


class Page:
    def __init__(self, browser, session):
        self.b = browser
        self.session = session

    def call(self, method, params=None, timeout=20):
        return self.b.call(method, params, self.session, timeout)

    def goto(self, url, timeout=20):
        self.call("Page.navigate", {"url": url})
        self.wait_for("document.readyState === 'complete'", timeout)

    def eval(self, expr, timeout=20):
        r = self.call("Runtime.evaluate", {"expression": expr, "returnByValue": True,
                                           "awaitPromise": True}, timeout)
        if "exceptionDetails" in r:
            d = r["exceptionDetails"]
            raise CdpError("%s: %s" % (expr[:80], (d.get("exception") or {}).get("description") or d.get("text")))
        return r["result"].get("value")

    def wait_for(self, expr, timeout=20, interval=0.2):
        """Waits until expr is truthy; returns its value, or raises CdpError with the last one."""
        deadline = time.monotonic() + timeout
        last = None
        while True:
            try:
                last = self.eval(expr)
            except CdpError as e:
                last = str(e)
            else:
                if last or isinstance(last, dict):  # an element comes back as {}
                    return last
            if time.monotonic() > deadline:
                raise CdpError("timed out after %g s waiting for %s (last: %r)" % (timeout, expr, last))
            time.sleep(interval)

    def console(self):
        """Console messages and uncaught exceptions so far, as text lines."""
        out = []
        for s, method, p in self.b.events:
            if s != self.session:
                continue
            if method == "Runtime.consoleAPICalled":
                out.append("console.%s: %s" % (p.get("type"), " ".join(
                    str(a.get("value", a.get("description", ""))) for a in p.get("args", []))))
            elif method == "Runtime.exceptionThrown":
                d = p.get("exceptionDetails", {})
                out.append("exception: %s" % ((d.get("exception") or {}).get("description") or d.get("text")))
        return out

    def rect(self, selector):
        return self.eval("(() => { const e = document.querySelector(%s); if (!e) return null;"
                         " const r = e.getBoundingClientRect();"
                         " return {x: r.x + scrollX, y: r.y + scrollY, width: r.width, height: r.height}; })()"
                         % json.dumps(selector))

    def screenshot(self, clip=None):
        params = {"format": "png", "captureBeyondViewport": False}
        if clip:
            params["clip"] = dict(clip, scale=1)
        return base64.b64decode(self.call("Page.captureScreenshot", params, timeout=30)["data"])

    def screenshot_of(self, selector):
        r = self.rect(selector)
        if not r or r["width"] < 1 or r["height"] < 1:
            raise CdpError("nothing to photograph at %s (%r)" % (selector, r))
        return self.screenshot(r)


def decode_png(data):
    """(width, height, rows of RGB(A) bytes) for 8-bit non-interlaced truecolour PNGs."""
    if data[:8] != b"\x89PNG\r\n\x1a\n":
        raise ValueError("not a PNG")
    pos, idat = 8, b""
    while pos < len(data):
        n, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + n]
        if kind == b"IHDR":
            w, h, depth, ctype, _, _, interlace = struct.unpack(">IIBBBBB", body)
            if depth != 8 or ctype not in (2, 6) or interlace:
                raise ValueError("unsupported PNG (depth %d, colour type %d)" % (depth, ctype))
            bpp = 3 if ctype == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + n
    raw = zlib.decompress(idat)
    stride = w * bpp
    rows, prev = [], bytearray(stride)
    for y in range(h):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - bpp] if i >= bpp else 0
            b = prev[i]
            c = prev[i - bpp] if i >= bpp else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + (a + b) // 2) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        rows.append(bytes(line))
        prev = line
    return w, h, bpp, rows


def count_non_background(png, tolerance=24):
    """(pixels differing from the most common colour by more than tolerance, total pixels)."""
    w, h, bpp, rows = decode_png(png)
    counts = {}
    for r in rows:
        for x in range(0, w * bpp, bpp):
            px = r[x:x + 3]
            counts[px] = counts.get(px, 0) + 1
    bg = max(counts, key=counts.get)
    busy = sum(n for px, n in counts.items()
               if max(abs(px[0] - bg[0]), abs(px[1] - bg[1]), abs(px[2] - bg[2])) > tolerance)
    return busy, w * h


def count_near(png, rgb, tolerance=40):
    """Pixels within tolerance (per channel) of the colour rgb, e.g. a plotted line's."""
    w, h, bpp, rows = decode_png(png)
    n = 0
    for r in rows:
        for x in range(0, w * bpp, bpp):
            if abs(r[x] - rgb[0]) <= tolerance and abs(r[x + 1] - rgb[1]) <= tolerance and \
                    abs(r[x + 2] - rgb[2]) <= tolerance:
                n += 1
    return n
