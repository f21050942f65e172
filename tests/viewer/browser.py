"""Headless Chromium driven over the DevTools protocol on a pipe (--remote-debugging-pipe), for the viewer's
browser tests and measurements.

Why not `chromium --dump-dom --virtual-time-budget=MS`: virtual time waits for pending HTTP fetches but not for
WebSocket data, so the DOM is dumped before the mesh arrives (checked with Chromium 150/156: the page says
"connected" with 0 triangles whatever the budget). Over the protocol the test waits in real time for what the
page shows, with the same rendering flags (SwiftShader WebGL)."""
import base64
import fcntl
import json
import os
import shutil
import struct
import subprocess
import tempfile
import time
import zlib

FLAGS = ["--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader", "--use-angle=swiftshader",
         "--disable-gpu-sandbox", "--no-first-run", "--no-default-browser-check", "--disable-extensions",
         "--mute-audio", "--disable-background-networking", "--disable-renderer-backgrounding",
         "--disable-background-timer-throttling", "--disable-backgrounding-occluded-windows"]


def find_chromium():
    for name in ("chromium", "chromium-browser", "google-chrome"):
        path = shutil.which(name)
        if path:
            return path
    return None


class Browser:
    def __init__(self, url, width=1280, height=800, chromium=None):
        exe = chromium or find_chromium()
        if not exe:
            raise RuntimeError("chromium not found (scripts/install_deps.sh installs it)")
        self.profile = tempfile.mkdtemp(prefix="vkmesh-chromium-")
        # Chromium's own messages, shown when it fails to start.
        self.log = open(os.path.join(self.profile, "chromium.log"), "w+")
        # fd 3: commands to the browser, fd 4: its replies and events (JSON, each ended by a NUL byte).
        to_browser_r, self.to_browser = os.pipe()
        self.from_browser, from_browser_w = os.pipe()
        # Above 4, so that the shell's redirections below cannot overwrite one before it is read.
        to_browser_r, from_browser_w = (self._above4(fd) for fd in (to_browser_r, from_browser_w))
        # bash (dash refuses fds above 9) puts the two pipe ends at fds 3 and 4, where Chromium expects them.
        self.proc = subprocess.Popen(
            ["/bin/bash", "-c", f'exec "$0" "$@" 3<&{to_browser_r} 4>&{from_browser_w}', exe, *FLAGS,
             f"--window-size={width},{height}", f"--user-data-dir={self.profile}", "--remote-debugging-pipe", "about:blank"],
            stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL, stderr=self.log, pass_fds=(to_browser_r, from_browser_w))
        os.close(to_browser_r)
        os.close(from_browser_w)
        self.next_id = 0
        self.pending = b""
        targets = self.call("Target.getTargets")["targetInfos"]
        page = next(t for t in targets if t["type"] == "page")
        self.session = self.call("Target.attachToTarget", targetId=page["targetId"], flatten=True)["sessionId"]
        self.call("Page.enable", session=True)
        self.call("Runtime.enable", session=True)
        self.call("Page.navigate", session=True, url=url)

    @staticmethod
    def _above4(fd):
        moved = fcntl.fcntl(fd, fcntl.F_DUPFD, 10)
        os.close(fd)
        return moved

    def _read_message(self):
        while b"\0" not in self.pending:
            chunk = os.read(self.from_browser, 1 << 20)
            if not chunk:
                self.log.seek(0)
                raise RuntimeError("chromium exited:\n" + "".join(l for l in self.log if "dbus" not in l)[-3000:])
            self.pending += chunk
        message, _, self.pending = self.pending.partition(b"\0")
        return json.loads(message)

    def call(self, method, session=False, **params):
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params}
        if session:
            message["sessionId"] = self.session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        while True:
            reply = self._read_message()
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                return reply["result"]

    def evaluate(self, expression):
        result = self.call("Runtime.evaluate", session=True, expression=expression, returnByValue=True)
        if "exceptionDetails" in result:
            raise RuntimeError(f"{expression}: {result['exceptionDetails']}")
        return result["result"].get("value")

    def text(self, element_id):
        return self.evaluate(f"(document.getElementById('{element_id}') || {{}}).textContent || null")

    def wait_for(self, predicate, timeout, poll=0.2):
        """Polls `predicate(self)` until it is true or `timeout` seconds have passed; returns its last value."""
        end = time.monotonic() + timeout
        while True:
            value = predicate(self)
            if value or time.monotonic() > end:
                return value
            time.sleep(poll)

    def screenshot_png(self):
        return base64.b64decode(self.call("Page.captureScreenshot", session=True, format="png")["data"])

    def screenshot(self, png=None):
        """The viewport (or the given PNG bytes) as (width, height, rows of RGB bytes)."""
        return decode_png(png or self.screenshot_png())

    def close(self):
        try:
            self.call("Browser.close")
        except Exception:
            pass
        try:
            self.proc.wait(timeout=10)
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
        for fd in (self.to_browser, self.from_browser):
            try:
                os.close(fd)
            except OSError:
                pass
        self.log.close()
        shutil.rmtree(self.profile, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def decode_png(data):
    """8-bit RGB or RGBA, non-interlaced PNG (what Chromium writes) -> (width, height, [bytes per row, RGB])."""
    assert data[:8] == b"\x89PNG\r\n\x1a\n", "not a PNG"
    pos, idat, width = 8, b"", 0
    while pos < len(data):
        length, kind = struct.unpack(">I4s", data[pos:pos + 8])
        body = data[pos + 8:pos + 8 + length]
        if kind == b"IHDR":
            width, height, depth, color, _, _, interlace = struct.unpack(">IIBBBBB", body)
            assert depth == 8 and color in (2, 6) and interlace == 0, (depth, color, interlace)
            channels = 3 if color == 2 else 4
        elif kind == b"IDAT":
            idat += body
        pos += 12 + length
    raw = zlib.decompress(idat)
    stride = width * channels
    rows, prev = [], bytearray(stride)
    for y in range(height):
        f = raw[y * (stride + 1)]
        line = bytearray(raw[y * (stride + 1) + 1:(y + 1) * (stride + 1)])
        for i in range(stride):
            a = line[i - channels] if i >= channels else 0
            b = prev[i]
            c = prev[i - channels] if i >= channels else 0
            if f == 1:
                line[i] = (line[i] + a) & 255
            elif f == 2:
                line[i] = (line[i] + b) & 255
            elif f == 3:
                line[i] = (line[i] + ((a + b) >> 1)) & 255
            elif f == 4:
                p = a + b - c
                pa, pb, pc = abs(p - a), abs(p - b), abs(p - c)
                line[i] = (line[i] + (a if pa <= pb and pa <= pc else b if pb <= pc else c)) & 255
        prev = line
        rows.append(bytes(line) if channels == 3 else bytes(v for i, v in enumerate(line) if i % 4 != 3))
    return width, height, rows
