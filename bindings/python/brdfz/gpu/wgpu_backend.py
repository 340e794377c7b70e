"""The check entry points as WGSL compute shaders through wgpu: Vulkan, Metal or D3D12 where there is a
GPU, Mesa's lavapipe (a software Vulkan driver) where there is none."""

import numpy as np

from . import slang
from .backend import ENTRIES, WORKGROUP, Backend, BackendUnavailable


def start():
    """(the wgpu module, its adapter): a GPU, or Mesa's lavapipe where there is none; BackendUnavailable
    without either."""
    try:
        import wgpu
    except ImportError as e:
        raise BackendUnavailable("wgpu is not installed (pip install wgpu)") from e
    found = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
    if found is None:
        raise BackendUnavailable("wgpu found no adapter (no GPU and no software Vulkan driver)")
    return wgpu, found


class WgpuBackend(Backend):
    name = "wgpu"

    def __init__(self):
        wgpu, found = start()
        self.adapter = found.info.get("device", "?")
        self.wgpu = wgpu
        self.limit = found.limits["max-storage-buffer-binding-size"]
        self.device = found.request_device_sync(
            required_limits={"max-storage-buffer-binding-size": self.limit, "max-buffer-size": found.limits["max-buffer-size"]})
        read_only = {"buffer": {"type": wgpu.BufferBindingType.read_only_storage}}
        entries = [{"binding": b, "visibility": wgpu.ShaderStage.COMPUTE, **read_only} for b in (0, 1, 2, 3, 5)]
        entries.append({"binding": 4, "visibility": wgpu.ShaderStage.COMPUTE,
                        "buffer": {"type": wgpu.BufferBindingType.storage}})
        self.group_layout = self.device.create_bind_group_layout(entries=entries)
        pipeline_layout = self.device.create_pipeline_layout(bind_group_layouts=[self.group_layout])
        source = slang.SHADERS / "check.slang"
        self.pipelines = {}
        for entry in ENTRIES:
            module = self.device.create_shader_module(code=slang.compile_entry(source, entry, "wgsl").decode())
            self.pipelines[entry] = self.device.create_compute_pipeline(
                layout=pipeline_layout, compute={"module": module, "entry_point": entry})
        self.material = self.desc = None

    def bind(self, layout):
        if len(layout.data) > self.limit:
            raise BackendUnavailable(f"the layout's {len(layout.data)} bytes exceed the adapter's storage buffer limit ({self.limit})")
        usage = self.wgpu.BufferUsage.STORAGE
        self.material = self.device.create_buffer_with_data(data=layout.data, usage=usage)
        self.desc = self.device.create_buffer_with_data(data=layout.desc.tobytes(), usage=usage)
        return self

    def _dispatch(self, entry, a, b, count, width):
        wgpu = self.wgpu
        storage = wgpu.BufferUsage.STORAGE
        inputs = [self.device.create_buffer_with_data(data=x.tobytes(), usage=storage) for x in (a, b)]
        n = self.device.create_buffer_with_data(data=np.array([count], np.uint32).tobytes(), usage=storage)
        result = self.device.create_buffer(size=4 * count * width, usage=storage | wgpu.BufferUsage.COPY_SRC)
        group = self.device.create_bind_group(layout=self.group_layout, entries=[
            {"binding": 0, "resource": {"buffer": self.material}},
            {"binding": 1, "resource": {"buffer": self.desc}},
            {"binding": 2, "resource": {"buffer": inputs[0]}},
            {"binding": 3, "resource": {"buffer": inputs[1]}},
            {"binding": 4, "resource": {"buffer": result}},
            {"binding": 5, "resource": {"buffer": n}}])
        encoder = self.device.create_command_encoder()
        compute = encoder.begin_compute_pass()
        compute.set_pipeline(self.pipelines[entry])
        compute.set_bind_group(0, group)
        compute.dispatch_workgroups((count + WORKGROUP - 1) // WORKGROUP)
        compute.end()
        self.device.queue.submit([encoder.finish()])
        return np.frombuffer(self.device.queue.read_buffer(result), np.float32)
