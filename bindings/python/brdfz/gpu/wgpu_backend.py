"""The shaders' check entry points (bindings/gpu/shaders/check.slang) as WGSL compute shaders through
wgpu: Vulkan, Metal or D3D12 where there is a GPU, Mesa's lavapipe (a software Vulkan driver) where
there is none."""

import numpy as np

from . import slang
from .layout import Layout

_WORKGROUP = 64
_MAX_GROUPS = 65535  # per dispatch dimension (WebGPU's default limit)


class BackendUnavailable(RuntimeError):
    pass


class WgpuBackend:
    name = "wgpu"

    def __init__(self):
        try:
            import wgpu
        except ImportError as e:
            raise BackendUnavailable("wgpu is not installed (pip install wgpu)") from e
        adapter = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
        if adapter is None:
            raise BackendUnavailable("wgpu found no adapter (no GPU and no software Vulkan driver)")
        self.adapter = adapter.info.get("device", "?")
        self.wgpu = wgpu
        self.limit = adapter.limits["max-storage-buffer-binding-size"]
        self.device = adapter.request_device_sync(
            required_limits={"max-storage-buffer-binding-size": self.limit, "max-buffer-size": adapter.limits["max-buffer-size"]})
        read_only = {"buffer": {"type": wgpu.BufferBindingType.read_only_storage}}
        entries = [{"binding": b, "visibility": wgpu.ShaderStage.COMPUTE, **read_only} for b in (0, 1, 2, 3, 5)]
        entries.append({"binding": 4, "visibility": wgpu.ShaderStage.COMPUTE,
                        "buffer": {"type": wgpu.BufferBindingType.storage}})
        self.group_layout = self.device.create_bind_group_layout(entries=entries)
        pipeline_layout = self.device.create_pipeline_layout(bind_group_layouts=[self.group_layout])
        source = slang.SHADERS / "check.slang"
        self.pipelines = {}
        for entry in ("check_eval", "check_rounding", "check_pdf", "check_sample"):
            module = self.device.create_shader_module(code=slang.compile_entry(source, entry, "wgsl").decode())
            self.pipelines[entry] = self.device.create_compute_pipeline(
                layout=pipeline_layout, compute={"module": module, "entry_point": entry})
        self.material = self.desc = None

    def bind(self, layout: Layout):
        """Uploads the material that the next calls evaluate."""
        if len(layout.data) > self.limit:
            raise BackendUnavailable(f"the layout's {len(layout.data)} bytes exceed the adapter's storage buffer limit ({self.limit})")
        usage = self.wgpu.BufferUsage.STORAGE
        self.material = self.device.create_buffer_with_data(data=layout.data, usage=usage)
        self.desc = self.device.create_buffer_with_data(data=layout.desc.tobytes(), usage=usage)
        return self

    def _run(self, entry, a, b, width):
        wgpu = self.wgpu
        n = len(a) // 3
        out = np.empty(n * width, np.float32)
        step = _WORKGROUP * _MAX_GROUPS
        for lo in range(0, max(n, 1), step):
            hi = min(n, lo + step)
            m = hi - lo
            if m == 0:
                break
            per_b = len(b) // n
            bufs = [self.device.create_buffer_with_data(data=np.ascontiguousarray(x, np.float32).tobytes(),
                                                        usage=wgpu.BufferUsage.STORAGE)
                    for x in (a[3 * lo:3 * hi], b[per_b * lo:per_b * hi])]
            count = self.device.create_buffer_with_data(data=np.array([m], np.uint32).tobytes(), usage=wgpu.BufferUsage.STORAGE)
            result = self.device.create_buffer(size=4 * m * width, usage=wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC)
            group = self.device.create_bind_group(layout=self.group_layout, entries=[
                {"binding": 0, "resource": {"buffer": self.material}},
                {"binding": 1, "resource": {"buffer": self.desc}},
                {"binding": 2, "resource": {"buffer": bufs[0]}},
                {"binding": 3, "resource": {"buffer": bufs[1]}},
                {"binding": 4, "resource": {"buffer": result}},
                {"binding": 5, "resource": {"buffer": count}}])
            encoder = self.device.create_command_encoder()
            compute = encoder.begin_compute_pass()
            compute.set_pipeline(self.pipelines[entry])
            compute.set_bind_group(0, group)
            compute.dispatch_workgroups((m + _WORKGROUP - 1) // _WORKGROUP)
            compute.end()
            self.device.queue.submit([encoder.finish()])
            out[width * lo:width * hi] = np.frombuffer(self.device.queue.read_buffer(result), np.float32)
        return out

    def eval(self, wi, wo):
        """f(wi, wo) per pair, (n, 3) float32."""
        return self._run("check_eval", np.ravel(wi), np.ravel(wo), 3).reshape(-1, 3)

    def rounding(self, wi, wo):
        """Each channel's scale of float rounding at each pair, (n, 3): f itself for tables; for
        factorisations the magnitude of the summed terms (the shaders' brdfz_eval_rounding)."""
        return self._run("check_rounding", np.ravel(wi), np.ravel(wo), 3).reshape(-1, 3)

    def pdf(self, wo, wi):
        return self._run("check_pdf", np.ravel(wo), np.ravel(wi), 1)

    def sample(self, wo, u):
        """(wi (n, 3), pdf (n,), weight (n, 3)) per draw."""
        r = self._run("check_sample", np.ravel(wo), np.ravel(u), 7).reshape(-1, 7)
        return r[:, :3], r[:, 3], r[:, 4:]
