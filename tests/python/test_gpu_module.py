"""The per-shading-point module (brdfz.gpu.module, `brdfz export`'s brdfz_module.*) as a renderer uses
it: its own shader includes the module and calls brdfz_eval, brdfz_pdf and brdfz_sample. In GLSL on
OpenGL (llvmpipe) and in WGSL on wgpu (lavapipe), such shaders give the exported kernels' results on a
real material's compact representations; GLSL ES 3.10 and HLSL compile to valid SPIR-V (glslang), CUDA
to PTX (NVRTC);
Metal has no compiler here, so only its names are checked."""

import re

import numpy as np
import pytest

from conftest import SHARED, exported_layouts, import_brdfz

RGL = SHARED / "data" / "rgl" / "satin_purple_rgb.bsdf"
PAIRS = 4096
SPECS = {"svd": "svd:rank=4,space=log,colour=shared,layout=hd_p,res=20x14x32,fit=lsq,symmetry=none,dtype=f16",
         "lobes": "analytic:lambert+ggx,starts=1"}

# A renderer's shader around the module, per language: one main per call, reading the directions (or u)
# from bindings 2 and 3, writing bindings 4, with the count at 5 (the kernels' bindings, so that the
# backends run these in their place).
GLSL_MAIN = """
layout(std430, binding = 2) readonly buffer RendererA { float a[]; };
layout(std430, binding = 3) readonly buffer RendererB { float b[]; };
layout(std430, binding = 4) buffer RendererOut { float o[]; };
layout(std430, binding = 5) readonly buffer RendererCount { uint count; };
layout(local_size_x = 64) in;
vec3 at(uint i, bool first) { return first ? vec3(a[3u * i], a[3u * i + 1u], a[3u * i + 2u]) : vec3(b[3u * i], b[3u * i + 1u], b[3u * i + 2u]); }
void main() {
    uint i = gl_GlobalInvocationID.x;
    if (i >= count) return;
    BODY
}
"""
GLSL_BODIES = {
    "brdfz_eval_kernel": "vec3 f = brdfz_eval(at(i, true), at(i, false)); o[3u * i] = f.x; o[3u * i + 1u] = f.y; o[3u * i + 2u] = f.z;",
    "brdfz_pdf_kernel": "o[i] = brdfz_pdf(at(i, true), at(i, false));",
    "brdfz_sample_kernel": "BrdfzSample s = brdfz_sample(at(i, true), vec2(b[2u * i], b[2u * i + 1u])); "
                           "o[7u * i] = s.wi.x; o[7u * i + 1u] = s.wi.y; o[7u * i + 2u] = s.wi.z; o[7u * i + 3u] = s.pdf; "
                           "o[7u * i + 4u] = s.weight.x; o[7u * i + 5u] = s.weight.y; o[7u * i + 6u] = s.weight.z;",
}
WGSL_MAIN = """
@binding(2) @group(0) var<storage, read> renderer_a : array<f32>;
@binding(3) @group(0) var<storage, read> renderer_b : array<f32>;
@binding(4) @group(0) var<storage, read_write> renderer_out : array<f32>;
@binding(5) @group(0) var<storage, read> renderer_count : array<u32>;
fn at(i : u32, first : bool) -> vec3<f32> {
    if (first) { return vec3<f32>(renderer_a[3u * i], renderer_a[3u * i + 1u], renderer_a[3u * i + 2u]); }
    return vec3<f32>(renderer_b[3u * i], renderer_b[3u * i + 1u], renderer_b[3u * i + 2u]);
}
@compute @workgroup_size(64)
fn ENTRY(@builtin(global_invocation_id) id : vec3<u32>) {
    let i = id.x;
    if (i >= renderer_count[0]) { return; }
    BODY
}
"""
WGSL_BODIES = {
    "brdfz_eval_kernel": "let f = brdfz_eval(at(i, true), at(i, false)); renderer_out[3u * i] = f.x; renderer_out[3u * i + 1u] = f.y; renderer_out[3u * i + 2u] = f.z;",
    "brdfz_pdf_kernel": "renderer_out[i] = brdfz_pdf(at(i, true), at(i, false));",
    "brdfz_sample_kernel": "let s = brdfz_sample(at(i, true), vec2<f32>(renderer_b[2u * i], renderer_b[2u * i + 1u])); "
                           "renderer_out[7u * i] = s.wi.x; renderer_out[7u * i + 1u] = s.wi.y; renderer_out[7u * i + 2u] = s.wi.z; "
                           "renderer_out[7u * i + 3u] = s.pdf; renderer_out[7u * i + 4u] = s.weight.x; "
                           "renderer_out[7u * i + 5u] = s.weight.y; renderer_out[7u * i + 6u] = s.weight.z;",
}


@pytest.fixture(scope="module")
def gpu_module():
    import_brdfz()
    from brdfz.gpu import slang

    try:
        slang._api()
    except slang.SlangError as e:
        pytest.skip(str(e))
    from brdfz.gpu import module

    return module


@pytest.fixture(scope="module")
def materials(tmp_path_factory):
    return exported_layouts(tmp_path_factory, RGL, SPECS, "module")


def inputs():
    from brdfz.gpu.check import pairs

    wi, wo = pairs(PAIRS, 3)
    u = np.random.default_rng(4).random((PAIRS, 2), dtype=np.float32)
    return wi, wo, u


def same_results(renderer, kernels, layout):
    """The renderer's shaders and the exported kernels on the same pairs and draws: equal floats."""
    wi, wo, u = inputs()
    renderer.bind(layout), kernels.bind(layout)
    np.testing.assert_array_equal(renderer.eval(wi, wo), kernels.eval(wi, wo))
    np.testing.assert_array_equal(renderer.pdf(wo, wi), kernels.pdf(wo, wi))
    for mine, theirs in zip(renderer.sample(wo, u), kernels.sample(wo, u)):
        np.testing.assert_array_equal(mine, theirs)
    assert np.count_nonzero(kernels.pdf(wo, wi)) > PAIRS // 2


@pytest.mark.parametrize("target", ["glsl", "essl", "hlsl", "wgsl", "cuda", "metal"])
def test_module_names_its_functions(gpu_module, target):
    code = gpu_module.module(target).decode()
    for name in ("brdfz_eval", "brdfz_pdf", "brdfz_sample"):
        assert re.search(rf"\b{name}\s*\(", code), name
    assert re.search(r"struct BrdfzSample\s*\{[^}]*\bwi\b[^}]*\bpdf\b[^}]*\bweight\b", code)
    from brdfz.gpu import slang

    assert "brdfz_module" not in code and "#line" not in code and "#version" not in code
    assert str(slang.SHADERS) not in code and str(slang.SHADERS.parent) not in code
    with pytest.raises(ValueError, match="no per-shading-point module"):
        gpu_module.module("spirv")


def install_glsl(renderer, code):
    renderer.shaders = {entry: renderer.ctx.compute_shader("#version 450\n" + code + GLSL_MAIN.replace("BODY", body))
                        for entry, body in GLSL_BODIES.items()}


def install_wgsl(renderer, code):
    layout = renderer.device.create_pipeline_layout(bind_group_layouts=[renderer.group_layout])
    for entry, body in WGSL_BODIES.items():
        shader = renderer.device.create_shader_module(code=code + WGSL_MAIN.replace("ENTRY", entry).replace("BODY", body))
        renderer.pipelines[entry] = renderer.device.create_compute_pipeline(layout=layout, compute={"module": shader, "entry_point": entry})


@pytest.mark.parametrize("target, backend_name, install", [("glsl", "gl", install_glsl), ("wgsl", "wgpu", install_wgsl)])
def test_module_in_a_renderer_shader(gpu_module, materials, target, backend_name, install):
    """A backend whose kernels are the renderer's shaders around the module, against one with the
    exported kernels."""
    from brdfz.gpu import BackendUnavailable, Layout, backend

    try:
        kernels, renderer = backend(backend_name), backend(backend_name)
    except BackendUnavailable as e:
        pytest.skip(str(e))
    install(renderer, gpu_module.module(target).decode())
    for path in materials.values():
        same_results(renderer, kernels, Layout(path))


# A renderer's compute shader that calls all three, per language glslang reads: (source, glslang's options).
RENDERERS = {
    "hlsl": ("""
RWStructuredBuffer<float> renderer_out : register(u1);
[numthreads(64, 1, 1)]
void main(uint3 id : SV_DispatchThreadID) {
    const float3 w = normalize(float3(0.3, 0.4, 0.8));
    const BrdfzSample s = brdfz_sample(w, float2(0.25, 0.5));
    renderer_out[id.x] = brdfz_eval(s.wi, w).x + brdfz_pdf(w, s.wi) + s.pdf + s.weight.y;
}
""", ["-D", "-S", "comp", "-e", "main"]),
    "essl": ("""
layout(std430, binding = 2) buffer RendererOut { float o[]; };
layout(local_size_x = 64) in;
void main() {
    vec3 w = normalize(vec3(0.3, 0.4, 0.8));
    BrdfzSample s = brdfz_sample(w, vec2(0.25, 0.5));
    o[gl_GlobalInvocationID.x] = brdfz_eval(s.wi, w).x + brdfz_pdf(w, s.wi) + s.pdf + s.weight.y;
}
""", ["-S", "comp"]),
}


@pytest.mark.parametrize("target", RENDERERS)
def test_module_compiles_in_a_renderer_shader(gpu_module, target, tmp_path):
    import shutil
    import subprocess

    glslang, spirv_val = shutil.which("glslangValidator"), shutil.which("spirv-val")
    if not glslang or not spirv_val:
        pytest.skip("glslang-tools and spirv-tools are not installed (scripts/setup-deps installs them)")
    main, options = RENDERERS[target]
    source = tmp_path / f"renderer.{target}"
    source.write_text(("#version 310 es\n" if target == "essl" else "") + gpu_module.module(target).decode() + main)
    spv = tmp_path / "renderer.spv"
    r = subprocess.run([glslang, "-V", *options, str(source), "-o", str(spv)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr
    r = subprocess.run([spirv_val, str(spv)], capture_output=True, text=True)
    assert r.returncode == 0, r.stdout + r.stderr


def test_cuda_module_compiles_in_a_renderer_kernel(gpu_module):
    from test_gpu_targets import compile_cuda

    ptx = compile_cuda(gpu_module.module("cuda") + b"""
extern "C" __global__ void renderer(float* out) {
    const float3 w = make_float3(0.3f, 0.4f, 0.8f);
    const BrdfzSample s = brdfz_sample(w, make_float2(0.25f, 0.5f));
    out[0] = brdfz_eval(s.wi, w).x + brdfz_pdf(w, s.wi) + s.pdf + s.weight.y;
}
""")
    assert b".entry renderer" in ptx and b"brdfz_module" not in ptx
