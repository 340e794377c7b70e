"""The check entry points as GLSL 4.5 compute shaders through moderngl on an EGL context without a
window: the GPU's OpenGL driver, or Mesa's llvmpipe where there is none."""

import numpy as np

from . import slang
from .backend import ENTRIES, WORKGROUP, Backend, BackendUnavailable


class GlBackend(Backend):
    name = "gl"

    def __init__(self):
        try:
            import moderngl
        except ImportError as e:
            raise BackendUnavailable("moderngl is not installed (pip install moderngl)") from e
        try:
            self.ctx = moderngl.create_standalone_context(backend="egl", require=450)
        except Exception as e:  # moderngl raises plain Exceptions for a missing EGL or GL 4.5
            raise BackendUnavailable(f"no OpenGL 4.5 context through EGL: {e}") from e
        self.adapter = self.ctx.info["GL_RENDERER"]
        self.limit = self.ctx.info["GL_MAX_SHADER_STORAGE_BLOCK_SIZE"]
        source = slang.SHADERS / "check.slang"
        self.shaders = {entry: self.ctx.compute_shader(slang.compile_entry(source, entry, "glsl").decode())
                        for entry in ENTRIES}
        self.material = self.desc = None

    def bind(self, layout):
        if len(layout.data) > self.limit:
            raise BackendUnavailable(f"the layout's {len(layout.data)} bytes exceed the driver's storage block limit ({self.limit})")
        self.material = self.ctx.buffer(layout.data)
        self.desc = self.ctx.buffer(layout.desc.tobytes())
        return self

    def _dispatch(self, entry, a, b, count, width):
        buffers = [self.material, self.desc, self.ctx.buffer(a.tobytes()), self.ctx.buffer(b.tobytes()),
                   self.ctx.buffer(reserve=4 * count * width), self.ctx.buffer(np.array([count], np.uint32).tobytes())]
        for binding, buffer in enumerate(buffers):
            buffer.bind_to_storage_buffer(binding)
        self.shaders[entry].run((count + WORKGROUP - 1) // WORKGROUP)
        self.ctx.memory_barrier()
        out = np.frombuffer(buffers[4].read(), np.float32).copy()
        for buffer in buffers[2:]:
            buffer.release()
        return out
