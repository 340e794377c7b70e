"""Every shading language the one shader source (bindings/gpu/shaders) is translated to, compiled by a
compiler that installs here: GLSL by glslangValidator (Vulkan), HLSL by glslang's HLSL front end, both
then checked by spirv-val; GLSL ES (3.10 compute kernels; 3.00 for WebGL2's entry points,
webgl.slang) by glslangValidator; CUDA by NVRTC (the nvidia-cuda-nvrtc wheel) to PTX. WGSL, GLSL and
GLSL ES 3.00 run in test_gpu_shaders.py. Metal has no compiler off macOS, and Debian 12's SPIRV-Tools predate the source
language Slang writes into its own SPIR-V: those two are only what Slang itself accepts."""

import ctypes
import glob
import importlib.util
import os
import re
import shutil
import subprocess

import pytest

from conftest import import_brdfz

ENTRIES = ["brdfz_eval_kernel", "check_rounding", "brdfz_pdf_kernel", "brdfz_sample_kernel"]


def entries(target):
    from brdfz.gpu.targets import WEBGL_ENTRIES

    return ENTRIES + list(WEBGL_ENTRIES) if target == "essl" else ENTRIES


@pytest.fixture(scope="module")
def compile_entry():
    import_brdfz()
    from brdfz.gpu import SlangError, emit

    try:
        emit(ENTRIES[0], "wgsl")
    except SlangError as e:
        pytest.skip(f"no Slang compiler: {e}")
    return emit


def tool(name):
    path = shutil.which(name)
    if not path:
        pytest.skip(f"{name} is not installed (scripts/setup-deps installs it)")
    return path


@pytest.mark.parametrize("target", ["wgsl", "glsl", "hlsl", "metal", "cuda", "spirv", "essl"])
def test_every_target_is_emitted(compile_entry, target):
    for entry in entries(target):
        code = compile_entry(entry, target)
        if target == "spirv":
            assert code[:4] == bytes.fromhex("03022307"), entry  # SPIR-V's magic number, little-endian
        else:
            # GLSL names every entry point main.
            assert ("void main()" if target in ("glsl", "essl") else entry) in code.decode(), (target, entry)


def test_essl_compiles(compile_entry, tmp_path):
    """GLSL ES 3.10 compute kernels (OpenGL ES 3.1), and WebGL2's GLSL ES 3.00 vertex and fragment entry
    points (webgl.slang)."""
    from brdfz.gpu.targets import WEBGL_ENTRIES

    glslang = tool("glslangValidator")
    for entry, stage in {**dict.fromkeys(ENTRIES, "compute"), **WEBGL_ENTRIES}.items():
        source = tmp_path / f"{entry}.{ {'compute': 'comp', 'vertex': 'vert', 'fragment': 'frag'}[stage] }"
        source.write_bytes(compile_entry(entry, "essl"))
        text = source.read_text()
        assert text.startswith("#version 310 es" if stage == "compute" else "#version 300 es"), entry
        r = subprocess.run([glslang, str(source)], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
        # Fragment shaders' float defaults to mediump, which SwiftShader computes in float32 but a
        # phone's GPU need not: every float value the shaders declare is highp.
        if stage == "fragment":
            loose = [line for line in text.splitlines() if re.search(r"\b(float|vec[234]|u?sampler2D)\s+\w", line) and "highp" not in line]
            assert not loose, (entry, loose[:5])


@pytest.mark.parametrize("target", ["glsl", "hlsl"])
def test_glsl_and_hlsl_compile_to_valid_spirv(compile_entry, target, tmp_path):
    glslang, spirv_val = tool("glslangValidator"), tool("spirv-val")
    for entry in ENTRIES:
        source = tmp_path / f"{entry}.{'comp' if target == 'glsl' else 'hlsl'}"
        source.write_bytes(compile_entry(entry, target))
        spv = tmp_path / f"{entry}.spv"
        args = ["-V", "--target-env", "vulkan1.1"] if target == "glsl" else ["-D", "-V", "-S", "comp", "-e", entry]
        r = subprocess.run([glslang, *args, str(source), "-o", str(spv)], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr
        r = subprocess.run([spirv_val, str(spv)], capture_output=True, text=True)
        assert r.returncode == 0, r.stdout + r.stderr


def nvrtc():
    spec = importlib.util.find_spec("nvidia")
    found = [p for d in (spec.submodule_search_locations if spec else [])
             for p in glob.glob(os.path.join(d, "cuda_nvrtc", "lib", "libnvrtc.so.*")) if "alt" not in p]
    if not found:
        pytest.skip("NVRTC is not installed (pip install nvidia-cuda-nvrtc-cu12; scripts/setup-deps does)")
    return ctypes.CDLL(sorted(found)[0])


def compile_cuda(source: bytes) -> bytes:
    """PTX of a CUDA source by NVRTC (skips without it); fails with NVRTC's log."""
    lib = nvrtc()
    program = ctypes.c_void_p()
    assert lib.nvrtcCreateProgram(ctypes.byref(program), source, b"brdfz.cu", 0, None, None) == 0
    try:
        # Slang's CUDA prelude folds infinities in constants (warning 222): not the shaders' code.
        options = [b"--gpu-architecture=compute_75", b"-std=c++17", b"-diag-suppress=222"]
        status = lib.nvrtcCompileProgram(program, len(options), (ctypes.c_char_p * len(options))(*options))
        size = ctypes.c_size_t()
        lib.nvrtcGetProgramLogSize(program, ctypes.byref(size))
        log = ctypes.create_string_buffer(size.value)
        lib.nvrtcGetProgramLog(program, log)
        assert status == 0, log.value.decode(errors="replace")
        lib.nvrtcGetPTXSize(program, ctypes.byref(size))
        ptx = ctypes.create_string_buffer(size.value)
        lib.nvrtcGetPTX(program, ptx)
        return ptx.value
    finally:
        lib.nvrtcDestroyProgram(ctypes.byref(program))


def test_cuda_compiles_to_ptx(compile_entry):
    for entry in ENTRIES:
        assert f".entry {entry}".encode() in compile_cuda(compile_entry(entry, "cuda")), entry
