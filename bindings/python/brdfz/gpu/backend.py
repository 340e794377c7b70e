"""What every backend gives the check: the shaders' check entry points (bindings/gpu/shaders/
kernels.slang, check.slang) over arrays of float32 directions, on one bound material."""

import numpy as np

WORKGROUP = 64        # kernels.slang's numthreads
MAX_GROUPS = 65535    # per dispatch dimension (WebGPU's and OpenGL's guaranteed minimum)
ENTRIES = ("brdfz_eval_kernel", "check_rounding", "brdfz_pdf_kernel", "brdfz_sample_kernel")


class BackendUnavailable(RuntimeError):
    pass


class Backend:
    name = "?"
    adapter = "?"  # the device it runs on, in words
    batch = WORKGROUP * MAX_GROUPS  # the most items a _dispatch

    def bind(self, layout):
        """Uploads the material (a Layout) that the next calls evaluate; returns self."""
        raise NotImplementedError

    def _dispatch(self, entry, a, b, count, width):
        """Runs `entry` on `count` items with inputs a and b (float32 arrays); returns count·width floats."""
        raise NotImplementedError

    def _run(self, entry, a, b, width):
        n = len(a) // 3
        per_b = len(b) // n if n else 0
        out = np.empty(n * width, np.float32)
        for lo in range(0, n, self.batch):
            hi = min(n, lo + self.batch)
            out[width * lo:width * hi] = self._dispatch(entry, np.ascontiguousarray(a[3 * lo:3 * hi], np.float32),
                                                        np.ascontiguousarray(b[per_b * lo:per_b * hi], np.float32), hi - lo, width)
        return out

    def eval(self, wi, wo):
        """f(wi, wo) per pair, (n, 3) float32."""
        return self._run("brdfz_eval_kernel", np.ravel(wi), np.ravel(wo), 3).reshape(-1, 3)

    def rounding(self, wi, wo):
        """Each channel's scale of float rounding at each pair, (n, 3): f itself for tables; for
        factorisations the magnitude of the summed terms (the shaders' brdfz_eval_rounding)."""
        return self._run("check_rounding", np.ravel(wi), np.ravel(wo), 3).reshape(-1, 3)

    def pdf(self, wo, wi):
        return self._run("brdfz_pdf_kernel", np.ravel(wo), np.ravel(wi), 1)

    def sample(self, wo, u):
        """(wi (n, 3), pdf (n,), weight (n, 3)) per draw."""
        r = self._run("brdfz_sample_kernel", np.ravel(wo), np.ravel(u), 7).reshape(-1, 7)
        return r[:, :3], r[:, 3], r[:, 4:]
