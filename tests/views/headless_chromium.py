"""Open an HTML file in headless Chromium and measure it, through the DevTools protocol.

Debian's ``chromium`` speaks the DevTools protocol over a pipe (``--remote-debugging-pipe``:
JSON messages ending in a NUL byte, the browser reads fd 3 and writes fd 4), so no client
library is needed. :func:`measure_page` loads a page at each width, waits for its load event
(every image fetched or failed), and runs :data:`MEASURE_JS` in it. Every wait has a deadline;
the browser is our own child process and is killed on the way out.
"""

from __future__ import annotations

import contextlib
import json
import os
import select
import shutil
import subprocess
import tempfile
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from offhost import off_host_turn

__all__ = ["MEASURE_JS", "chromium_binary", "measure_page"]

#: In the page: the viewport width, every image and whether it loaded, every element that
#: reaches beyond the viewport on either side.
MEASURE_JS = """
(() => {
  const viewport = document.documentElement.clientWidth;
  const images = [...document.images].map((img) => ({
    src: img.getAttribute("src"),
    loaded: img.complete && img.naturalWidth > 0,
    naturalWidth: img.naturalWidth,
    shownWidth: img.getBoundingClientRect().width,
  }));
  const overflowing = [];
  for (const el of document.body.querySelectorAll("*")) {
    const box = el.getBoundingClientRect();
    if (box.width === 0 && box.height === 0) continue;
    if (box.right > viewport + 0.5 || box.left < -0.5) {
      overflowing.push({
        tag: el.tagName.toLowerCase(),
        text: (el.textContent || "").trim().slice(0, 60),
        left: box.left,
        right: box.right,
      });
    }
  }
  return {
    viewport,
    scrollWidth: document.documentElement.scrollWidth,
    images,
    overflowing,
  };
})()
"""


#: Chromium's own traffic, off: a page here is a local file, and a test sends nothing off the
#: host. Without these a start sent about 200 packets on eth0 (name look-ups, the component
#: updater, its background services); every host name now resolves to nothing, and anything
#: that still asks for the network meets a dead proxy on loopback (port 9, discard).
_QUIET_NETWORK_FLAGS = (
    "--host-resolver-rules=MAP * ~NOTFOUND",
    "--proxy-server=127.0.0.1:9",
    "--proxy-bypass-list=<-loopback>",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-domain-reliability",
    "--disable-sync",
    "--no-pings",
    "--no-default-browser-check",
    "--disable-features=MediaRouter,OptimizationHints,Translate,AutofillServerCommunication",
)


def chromium_binary() -> str | None:
    """The installed Chromium (Debian's package ``chromium``), or None."""
    for name in ("chromium", "chromium-browser"):
        found = shutil.which(name)
        if found:
            return found
    return None


class _DevTools:
    """A DevTools session over the browser's pipe: commands with ids, events by name."""

    def __init__(self, to_browser: int, from_browser: int, deadline: float) -> None:
        self.to_browser, self.from_browser, self.deadline = to_browser, from_browser, deadline
        self.buffer = b""
        self.next_id = 0
        self.events: list[dict[str, Any]] = []

    def _read_message(self) -> dict[str, Any]:
        while b"\0" not in self.buffer:
            left = self.deadline - time.monotonic()
            if left <= 0:
                raise TimeoutError("chromium did not answer in time")
            ready, _, _ = select.select([self.from_browser], [], [], left)
            if ready:
                chunk = os.read(self.from_browser, 1 << 16)
                if not chunk:
                    raise ConnectionError("chromium closed its DevTools pipe")
                self.buffer += chunk
        message, self.buffer = self.buffer.split(b"\0", 1)
        data: dict[str, Any] = json.loads(message)
        return data

    def call(self, method: str, session: str | None = None, **params: Any) -> dict[str, Any]:
        """Send a command and wait for its result (events meanwhile are kept)."""
        self.next_id += 1
        message: dict[str, Any] = {"id": self.next_id, "method": method, "params": params}
        if session is not None:
            message["sessionId"] = session
        os.write(self.to_browser, json.dumps(message).encode() + b"\0")
        while True:
            reply = self._read_message()
            if reply.get("id") == self.next_id:
                if "error" in reply:
                    raise RuntimeError(f"{method}: {reply['error']}")
                result: dict[str, Any] = reply.get("result", {})
                return result
            self.events.append(reply)

    def wait_event(self, method: str) -> dict[str, Any]:
        """Wait for the next event named ``method`` (one already received counts)."""
        while True:
            for i, event in enumerate(self.events):
                if event.get("method") == method:
                    return self.events.pop(i)
            self.events.append(self._read_message())


def measure_page(
    path: Path, widths: Sequence[int], *, timeout_s: float = 60.0, binary: str | None = None
) -> dict[int, dict[str, Any]]:
    """Load ``path`` in headless Chromium at each width and return :data:`MEASURE_JS`'s result.

    Raises:
        FileNotFoundError: no Chromium installed.
        TimeoutError: the browser took longer than ``timeout_s`` in all.
    """
    binary = binary or chromium_binary()
    if binary is None:
        raise FileNotFoundError("chromium is not installed")
    with off_host_turn():  # never beside a ROS 2 test's packet count (tests/offhost.py)
        return _measure_page(binary, path, widths, timeout_s)


def _measure_page(
    binary: str, path: Path, widths: Sequence[int], timeout_s: float
) -> dict[int, dict[str, Any]]:
    to_browser_r, to_browser_w = os.pipe()
    from_browser_r, from_browser_w = os.pipe()
    profile = tempfile.mkdtemp(prefix="ftcomp-chromium-")

    def pipes_on_3_and_4() -> None:  # in the child, before exec
        os.dup2(to_browser_r, 3)
        os.dup2(from_browser_w, 4)

    args = [
        binary,
        "--headless",
        "--disable-gpu",
        "--no-first-run",
        "--hide-scrollbars",
        "--remote-debugging-pipe",
        f"--user-data-dir={profile}",
        *_QUIET_NETWORK_FLAGS,
    ]
    if hasattr(os, "geteuid") and os.geteuid() == 0:
        args.append("--no-sandbox")  # Chromium refuses to run as root with its sandbox
    browser = subprocess.Popen(
        [*args, "about:blank"],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
        pass_fds=(3, 4),
        preexec_fn=pipes_on_3_and_4,
    )
    os.close(to_browser_r)
    os.close(from_browser_w)
    results: dict[int, dict[str, Any]] = {}
    try:
        tools = _DevTools(to_browser_w, from_browser_r, time.monotonic() + timeout_s)
        target = tools.call("Target.createTarget", url="about:blank")["targetId"]
        session = tools.call("Target.attachToTarget", targetId=target, flatten=True)["sessionId"]
        tools.call("Page.enable", session)
        for i, width in enumerate(widths):
            tools.call(
                "Emulation.setDeviceMetricsOverride",
                session,
                width=width,
                height=900,
                deviceScaleFactor=1,
                mobile=False,
            )
            if i == 0:
                tools.call("Page.navigate", session, url=path.resolve().as_uri())
                tools.wait_event("Page.loadEventFired")
            value = tools.call(
                "Runtime.evaluate", session, expression=MEASURE_JS, returnByValue=True
            )
            results[width] = value["result"]["value"]
        with contextlib.suppress(ConnectionError, TimeoutError, RuntimeError):
            tools.call("Browser.close")  # the browser may close the pipe before it answers
    finally:
        os.close(to_browser_w)
        os.close(from_browser_r)
        try:
            browser.wait(timeout=5)
        except subprocess.TimeoutExpired:
            browser.kill()
            browser.wait(timeout=5)
        shutil.rmtree(profile, ignore_errors=True)
    return results
