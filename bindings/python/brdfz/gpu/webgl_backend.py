"""The check as WebGL2 fragment shaders (GLSL ES 3.00, the essl target) in headless Chromium, driven by
Playwright: SwiftShader, Chromium's software Vulkan under ANGLE, renders. The browser is the system's
(Debian's chromium, or $BRDFZ_CHROMIUM), not one Playwright downloads; the page is blank and loads
only webgl.js, so nothing is fetched."""

import atexit
import base64
import os
import re
import shutil
import weakref
from pathlib import Path

import numpy as np

from . import slang, targets
from .backend import Backend, BackendUnavailable

# Software WebGL whatever the machine has: newer Chromium serves WebGL from SwiftShader only when told
# it may.
FLAGS = ["--use-angle=swiftshader", "--enable-unsafe-swiftshader"]
WIDTH = 1024  # texels a row of the direction textures and render targets
ROWS = 64     # rows a draw: one draw's time bounded, as Chromium's GPU watchdog ends a GPU process that hangs
# The check's compute entry points' WebGL equivalents, and how many RGBA32F targets each writes.
ENTRIES = {"brdfz_eval_kernel": ("webgl_eval", 1), "check_rounding": ("webgl_rounding", 1),
           "brdfz_pdf_kernel": ("webgl_pdf", 1), "brdfz_sample_kernel": ("webgl_sample", 2)}


def _texture_width():
    """The material texture's row length, as webgl.slang defines it for math.slang."""
    return int(re.search(r"#define BRDFZ_TEXTURE_WIDTH (\d+)", (slang.SHADERS / "webgl.slang").read_text()).group(1))


def chromium():
    path = os.environ.get("BRDFZ_CHROMIUM") or next(
        filter(None, map(shutil.which, ("chromium", "chromium-browser", "google-chrome"))), None)
    if not path:
        raise BackendUnavailable("no Chromium (Debian: apt-get install chromium; or set BRDFZ_CHROMIUM)")
    return path


_started = {}  # the process's Playwright driver and browser
# Pages of backends gone, closed at the next start: not from their finaliser, which may run in the
# middle of a Playwright call.
_stale = []


def _chromium_started():
    """One browser for the process, from one Playwright driver (its sync API runs one per thread);
    each backend has its own page. Both are stopped at exit."""
    while _stale:
        _stale.pop().close()
    if "browser" not in _started:
        executable = chromium()
        try:
            from playwright.sync_api import Error, sync_playwright
        except ImportError as e:
            raise BackendUnavailable("playwright is not installed (pip install playwright)") from e
        if "driver" not in _started:
            _started["driver"] = sync_playwright().start()
            atexit.register(_started["driver"].stop)
        try:
            _started["browser"] = _started["driver"].chromium.launch(executable_path=executable, args=FLAGS)
        except Error as e:
            raise BackendUnavailable(f"Chromium ({executable}) does not start: {str(e).splitlines()[0]}") from e
    return _started["browser"]


def _b64(array):
    return base64.b64encode(np.ascontiguousarray(array).tobytes()).decode()


class WebglBackend(Backend):
    name = "webgl"
    batch = WIDTH * ROWS

    def __init__(self):
        shaders = {"vertex": targets.emit("webgl_vertex", "essl").decode(),
                   "fragments": {e: targets.emit(e, "essl").decode() for e, _ in ENTRIES.values()}}
        self.page = _chromium_started().new_page()
        weakref.finalize(self, _stale.append, self.page)
        # The handlers hold the list, not self: the page outlives a backend until _stale closes it.
        errors = self.errors = []
        self.page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: errors.append(str(e)))
        self.page.add_script_tag(path=str(Path(__file__).with_name("webgl.js")))
        try:
            self.adapter = self._call("brdfz.init", shaders)
        except RuntimeError as e:
            if "unavailable: " in str(e):
                raise BackendUnavailable(str(e).split("unavailable: ", 1)[1].splitlines()[0]) from e
            raise
        self.max_size = self._call("brdfz.maxTextureSize")
        self.texture_width = _texture_width()

    def _call(self, function, *args):
        """A function of webgl.js in the page; its exceptions and the console's errors raise here."""
        from playwright.sync_api import Error

        try:
            result = self.page.evaluate(f"(args) => {function}(...args)", list(args))
        except Error as e:
            raise RuntimeError(f"webgl: {function}: {e.message}") from e
        if self.errors:
            message = "; ".join(self.errors)
            self.errors.clear()
            raise RuntimeError(f"webgl: {function}: console: {message}")
        return result

    def bind(self, layout):
        words = np.frombuffer(layout.data, "<u4")
        rows = -(-len(words) // self.texture_width)
        if rows > self.max_size:
            raise BackendUnavailable(f"the layout's {len(layout.data)} bytes exceed the largest texture "
                                     f"({self.texture_width} × {self.max_size} words)")
        data = np.zeros(rows * self.texture_width, "<u4")
        data[:len(words)] = words
        desc = layout.desc.view("<u4").reshape(len(layout.desc), -1)
        self._call("brdfz.bind", _b64(data), self.texture_width, _b64(desc), desc.shape[1])
        return self

    def _dispatch(self, entry, a, b, count, width):
        fragment, outputs = ENTRIES[entry]
        rows = -(-count // WIDTH)
        texels = []
        for x in (a, b):
            t = np.zeros((rows * WIDTH, 4), np.float32)
            t[:count, :len(x) // count] = x.reshape(count, -1)
            texels.append(_b64(t))
        out = np.frombuffer(base64.b64decode(self._call("brdfz.run", fragment, *texels, WIDTH, outputs)), np.float32)
        out = out.reshape(outputs, rows * WIDTH, 4)[:, :count]
        # Per item: the first target's components, then the second's (sample: wi, pdf, then weight).
        return np.concatenate(list(out), axis=1)[:, :width].ravel()
