#!/usr/bin/env python3
"""Opens a page written by `lagrange simulate --animate` in headless Chromium and checks it.

Chromium is driven over its DevTools protocol on a pipe (--remote-debugging-pipe), so nothing
but Chromium and the Python standard library is needed and no port is opened. The checks:

- the page loads with no console error, no uncaught exception and no request that leaves the
  file (no network: every request must be for the page itself);
- stepping the time slider changes the picture: the scene's canvas, captured at two slider
  positions, differs in a good number of pixels;
- the slider and the clock agree (`t = …` follows the slider).

With --still POSITION:FILE.png it also saves the page's panels at that slider position
(0 to 1000), the pictures the README shows.

Exit 0 when every check passes; otherwise 1, with what failed on stderr. Never waits forever:
every step has a deadline and Chromium is killed at the end.
"""

import argparse
import base64
import json
import os
import pathlib
import select
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zlib

# Chromium's flags for a machine without a display or a network: no GPU, no sandbox (it may
# run as root in CI), and none of the background services that would try to reach the
# network at start.
CHROMIUM_FLAGS = [
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--disable-default-apps",
    "--disable-extensions",
    "--no-first-run",
    "--no-default-browser-check",
    "--mute-audio",
    "--hide-scrollbars",
    "--remote-debugging-pipe",
]

STEP_SECONDS = 30.0
WIDTH, HEIGHT = 1100, 640


class Failure(Exception):
    pass


class Browser:
    """Chromium with one page, spoken to over the DevTools pipe."""

    def __init__(self, executable, profile):
        # Chromium reads commands from fd 3 and writes replies to fd 4.
        to_chromium_read, self.to_chromium = os.pipe()
        self.from_chromium, from_chromium_write = os.pipe()

        def wire_pipes():
            # Through fds out of the way first, in case a pipe's end already sits at 3 or 4.
            os.dup2(to_chromium_read, 100)
            os.dup2(from_chromium_write, 101)
            os.dup2(100, 3)
            os.dup2(101, 4)

        self.process = subprocess.Popen(
            [executable, *CHROMIUM_FLAGS, f"--user-data-dir={profile}", "about:blank"],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            preexec_fn=wire_pipes,
            pass_fds=(3, 4),
        )
        os.close(to_chromium_read)
        os.close(from_chromium_write)
        self.buffer = b""
        self.next_id = 0
        self.events = []
        self.session = None

    def close(self):
        try:
            self.process.kill()
            self.process.wait(timeout=STEP_SECONDS)
        except (OSError, subprocess.TimeoutExpired):
            pass
        for fd in (self.to_chromium, self.from_chromium):
            try:
                os.close(fd)
            except OSError:
                pass

    def _read_message(self, deadline):
        while b"\0" not in self.buffer:
            left = deadline - time.monotonic()
            if left <= 0:
                raise Failure("Chromium did not answer in time")
            ready, _, _ = select.select([self.from_chromium], [], [], left)
            if not ready:
                continue
            chunk = os.read(self.from_chromium, 1 << 20)
            if not chunk:
                raise Failure("Chromium closed its pipe (it may have crashed)")
            self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        return json.loads(message)

    def send(self, method, params=None, session=True):
        """Sends a command and returns its result; events met meanwhile are kept."""
        self.next_id += 1
        message = {"id": self.next_id, "method": method, "params": params or {}}
        if session and self.session:
            message["sessionId"] = self.session
        os.write(self.to_chromium, json.dumps(message).encode() + b"\0")
        deadline = time.monotonic() + STEP_SECONDS
        while True:
            reply = self._read_message(deadline)
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise Failure(f"{method}: {reply['error'].get('message')}")
                return reply.get("result", {})
            if "method" in reply:
                self.events.append(reply)

    def wait_for(self, event):
        deadline = time.monotonic() + STEP_SECONDS
        while True:
            for e in self.events:
                if e.get("method") == event:
                    self.events.remove(e)
                    return e
            self.events.append(self._read_message(deadline))

    def evaluate(self, expression):
        result = self.send(
            "Runtime.evaluate",
            {"expression": expression, "awaitPromise": True, "returnByValue": True},
        )
        if "exceptionDetails" in result:
            raise Failure(f"script failed: {result['exceptionDetails'].get('text')}")
        return result.get("result", {}).get("value")

    def open(self, url):
        target = self.send("Target.createTarget", {"url": "about:blank"}, session=False)
        attached = self.send(
            "Target.attachToTarget", {"targetId": target["targetId"], "flatten": True}, session=False
        )
        self.session = attached["sessionId"]
        for domain in ("Page", "Runtime", "Log", "Network"):
            self.send(f"{domain}.enable")
        self.send(
            "Emulation.setDeviceMetricsOverride",
            {"width": WIDTH, "height": HEIGHT, "deviceScaleFactor": 1, "mobile": False},
        )
        self.send("Page.navigate", {"url": url})
        self.wait_for("Page.loadEventFired")

    def screenshot(self, selector):
        box = self.evaluate(
            f"(() => {{ const r = document.querySelector({json.dumps(selector)})"
            ".getBoundingClientRect(); return [r.x, r.y, r.width, r.height]; })()"
        )
        x, y, w, h = box
        shot = self.send(
            "Page.captureScreenshot",
            {"format": "png", "clip": {"x": x, "y": y, "width": w, "height": h, "scale": 1}},
        )
        return base64.b64decode(shot["data"])


def pixels(png):
    """The RGBA bytes of an 8-bit, non-interlaced PNG (what Chromium writes), row by row."""
    if png[:8] != b"\x89PNG\r\n\x1a\n":
        raise Failure("the screenshot is not a PNG")
    at, data, header = 8, b"", None
    while at < len(png):
        (length,) = struct.unpack(">I", png[at : at + 4])
        kind = png[at + 4 : at + 8]
        body = png[at + 8 : at + 8 + length]
        if kind == b"IHDR":
            header = struct.unpack(">IIBBBBB", body)
        elif kind == b"IDAT":
            data += body
        at += 12 + length
    width, height, depth, colour, _, _, interlace = header
    channels = {2: 3, 6: 4}.get(colour)
    if depth != 8 or channels is None or interlace != 0:
        raise Failure(f"unexpected PNG format (depth {depth}, colour type {colour})")
    raw = zlib.decompress(data)
    stride = width * channels
    rows, previous = [], bytearray(stride)
    for r in range(height):
        start = r * (stride + 1)
        kind, line = raw[start], bytearray(raw[start + 1 : start + 1 + stride])
        for i in range(stride):
            left = line[i - channels] if i >= channels else 0
            up = previous[i]
            corner = previous[i - channels] if i >= channels else 0
            if kind == 1:
                line[i] = (line[i] + left) & 255
            elif kind == 2:
                line[i] = (line[i] + up) & 255
            elif kind == 3:
                line[i] = (line[i] + (left + up) // 2) & 255
            elif kind == 4:
                p = left + up - corner
                pa, pb, pc = abs(p - left), abs(p - up), abs(p - corner)
                line[i] = (line[i] + (left if pa <= pb and pa <= pc else up if pb <= pc else corner)) & 255
        rows.append(bytes(line))
        previous = line
    return width, height, channels, rows


def differing_pixels(a, b):
    wa, ha, ca, ra = pixels(a)
    wb, hb, cb, rb = pixels(b)
    if (wa, ha) != (wb, hb):
        return wa * ha
    count = 0
    for row_a, row_b in zip(ra, rb):
        for x in range(wa):
            if row_a[x * ca : x * ca + 3] != row_b[x * cb : x * cb + 3]:
                count += 1
    return count


def problems_in(events, page_url):
    """Console errors, uncaught exceptions and requests for anything but the page itself."""
    found = []
    for e in events:
        method, params = e.get("method"), e.get("params", {})
        if method == "Runtime.exceptionThrown":
            details = params.get("exceptionDetails", {})
            text = details.get("exception", {}).get("description") or details.get("text")
            found.append(f"uncaught exception: {text}")
        elif method == "Runtime.consoleAPICalled" and params.get("type") in ("error", "assert"):
            args = [a.get("value", a.get("description")) for a in params.get("args", [])]
            found.append(f"console.{params['type']}: {args}")
        elif method == "Log.entryAdded" and params.get("entry", {}).get("level") == "error":
            found.append(f"console error: {params['entry'].get('text')}")
        elif method == "Network.requestWillBeSent":
            url = params.get("request", {}).get("url", "")
            if url != page_url and not url.startswith("data:"):
                found.append(f"a request left the page: {url}")
    return found


def check(page, chromium, stills):
    page_url = page.resolve().as_uri()
    profile = tempfile.mkdtemp(prefix="lagrange-chromium-")
    browser = Browser(chromium, profile)
    try:
        browser.open(page_url)
        set_slider = (
            "(async (v) => {{ const s = document.getElementById('time'); s.value = String(v);"
            " s.dispatchEvent(new Event('input')); await new Promise(r => requestAnimationFrame("
            "() => requestAnimationFrame(r))); return document.getElementById('clock')"
            ".textContent; }})({})"
        )
        clocks, shots = [], []
        for position in (0, 500):
            clocks.append(browser.evaluate(set_slider.format(position)))
            shots.append(browser.screenshot("#scene"))
        for position, path in stills:
            browser.evaluate(set_slider.format(position))
            path.write_bytes(browser.screenshot("#panels"))
        # Events that arrived after the last command.
        browser.evaluate("new Promise(r => setTimeout(r, 200))")
        failures = problems_in(browser.events, page_url)
        if clocks[0] != "t = 0.000 s" or clocks[0] == clocks[1]:
            failures.append(f"the clock does not follow the slider: {clocks}")
        width, height, _, _ = pixels(shots[0])
        changed = differing_pixels(shots[0], shots[1])
        if changed < max(50, width * height // 1000):
            failures.append(
                f"the picture hardly changes with time: {changed} of {width * height} pixels"
            )
        return failures, changed, clocks
    finally:
        browser.close()
        shutil.rmtree(profile, ignore_errors=True)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("page", type=pathlib.Path)
    parser.add_argument("--chromium", default=shutil.which("chromium") or "chromium")
    parser.add_argument("--still", action="append", default=[], metavar="POSITION:FILE.png")
    args = parser.parse_args()
    stills = []
    for item in args.still:
        position, _, path = item.partition(":")
        stills.append((int(position), pathlib.Path(path)))
    try:
        failures, changed, clocks = check(args.page, args.chromium, stills)
    except Failure as e:
        failures, changed, clocks = [str(e)], 0, []
    if failures:
        for f in failures:
            print(f"{args.page}: {f}", file=sys.stderr)
        return 1
    print(f"{args.page}: {changed} pixels change between {clocks[0]} and {clocks[1]}; no errors")
    return 0


if __name__ == "__main__":
    sys.exit(main())
