"""brdfz export IN -o DIR --target T (brdfz.gpu.export): for every target, the files brdfz.json lists,
their sizes and slots; the error it records equals brdfz.metrics' over the same pairs; the exported
kernels are the ones the compilers check (test_gpu_targets.py) and, run from the exported files alone
on wgpu and OpenGL, give the same bits as the harness that test_gpu_shaders.py checks against the
library; the command forwards to Python, and bad input leaves one line and no files."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from conftest import SHARED, import_brdfz, run

RGL = SHARED / "data" / "rgl" / "cc_ibiza_sunset_rgb.bsdf"
# A ≤ 16 KB representation (asserted below) with the compact sampler.
SPEC = "svd:rank=10,space=cos,colour=shared,res=25x20x14,dwarp=0.9,fit=lsq,symmetry=bilateral,dtype=f16"
TARGETS = ("glsl", "essl", "hlsl", "wgsl", "cuda", "metal", "slang")


@pytest.fixture(scope="module")
def source():
    brdfz = import_brdfz()
    if not RGL.exists():
        pytest.skip(f"../shared is missing ({RGL})")
    try:
        from brdfz.gpu import SlangError, emit

        emit("brdfz_eval_kernel", "wgsl")
    except SlangError as e:
        pytest.skip(f"no Slang compiler: {e}")
    return brdfz.load(RGL)


@pytest.fixture(scope="module")
def exports(source, tmp_path_factory):
    from brdfz.gpu import export

    brdfz = import_brdfz()
    out = tmp_path_factory.mktemp("export")
    # One target builds the representation from the file; the others export that Brdf, measured against
    # the same source, as a script that compressed once would.
    built = brdfz.compress(source, SPEC)
    return {t: (out / t, export(RGL, out / t, t, repr=SPEC, error_pairs=4096) if t == "wgsl" else
                export(built, out / t, t, reference=source, error_pairs=4096)) for t in TARGETS}


@pytest.mark.parametrize("target", TARGETS)
def test_descriptor_lists_what_is_written(exports, target):
    folder, d = exports[target]
    on_disk = json.loads((folder / "brdfz.json").read_text())
    assert on_disk == d
    assert sorted(d["files"]) == sorted(str(p.relative_to(folder)) for p in folder.rglob("*") if p.is_file())
    assert d["target"] == target and d["representation"].startswith("svd rank 10")
    assert d["error"]["over"] == "directions" and d["error"]["cos_rmse_rel"] == exports["wgsl"][1]["error"]["cos_rmse_rel"]
    if target == "wgsl":
        assert d["build_spec"].startswith("svd:rank=10") and d["source"] == RGL.name
    assert d["bytes"] <= 16384
    for b in d["buffers"]:
        assert (folder / b["file"]).stat().st_size == b["bytes"]
    desc = d["buffers"][1]
    assert desc["count"] * desc["stride"] == desc["bytes"] and len(desc["fields"]) * 4 == desc["stride"]
    # The material buffer starts with the runtime layout's magic, and holds the layout as brdfz writes it.
    assert (folder / "material.bin").read_bytes()[:8] == b"\x89BZRT\r\n\x1a"
    assert [k["entry"] for k in d["kernels"]] == ["brdfz_eval_kernel", "brdfz_pdf_kernel", "brdfz_sample_kernel"]
    note = (folder / "INTEGRATION.md").read_text()
    assert "brdfz_sample_kernel" in note and "material.bin" in note


def test_recorded_error_is_measured(source, exports):
    """The error in brdfz.json is brdfz.metrics' over the same direction pairs (a deterministic draw),
    so it can be reproduced; and it is the figure of this representation, not of another."""
    brdfz = import_brdfz()
    _, d = exports["wgsl"]
    built = brdfz.compress(source, SPEC)
    m = brdfz.metrics(source, built, over="directions", directions=4096)
    assert d["error"]["over"] == "directions" and d["error"]["pairs"] == 4096
    assert d["error"]["cos_rmse_rel"] == pytest.approx(m.cos_rmse_rel.mean, rel=1e-12)
    coarse = brdfz.compress(source, "svd:rank=1,space=cos,res=8x6x8")
    assert brdfz.metrics(source, coarse, over="directions", directions=4096).cos_rmse_rel.mean > 1.5 * d["error"]["cos_rmse_rel"]


@pytest.mark.parametrize("target", [t for t in TARGETS if t != "slang"])
def test_kernels_are_the_checked_ones(exports, target):
    """The exported kernel files are what emit() gives for kernels.slang: the code test_gpu_targets.py
    compiles with each target's compiler."""
    from brdfz.gpu import emit, slang

    folder, d = exports[target]
    for k in d["kernels"]:
        assert (folder / k["file"]).read_bytes() == emit(k["entry"], target, slang.SHADERS / "kernels.slang")
    # Every buffer has a slot, read from the emitted code.
    slots = {d["buffers"][0]["slot"], d["buffers"][1]["slot"], *d["io_slots"].values()}
    assert len(slots) == 6, d


@pytest.mark.parametrize("target", TARGETS)
def test_module_is_the_tested_one(exports, target):
    """Per-shading-point functions for every target: the module file is brdfz.gpu.module's
    (test_gpu_module.py runs it inside a renderer's shaders), documented with the functions it holds."""
    from brdfz.gpu.module import MODULE_TARGETS, module

    folder, d = exports[target]
    note = (folder / "INTEGRATION.md").read_text()
    assert d["functions"] == ["float3 brdfz_eval(float3 wi, float3 wo)", "float brdfz_pdf(float3 wo, float3 wi)",
                              "BrdfzSample brdfz_sample(float3 wo, float2 u)"]
    assert d["module"] in d["files"] and (folder / d["module"]).is_file()
    if target in MODULE_TARGETS:
        assert (folder / d["module"]).read_bytes() == module(target)
        assert "## Per shading point" in note and d["module"] in note


def test_essl_carries_webgl2_passes(exports):
    """GLSL ES: the 3.10 compute kernels and WebGL2's 3.00 render passes (what the webgl backend runs
    against the library), with the textures' shapes the passes read."""
    from brdfz.gpu import emit

    folder, d = exports["essl"]
    w = d["webgl2"]
    for name in [w["vertex"]] + [p["file"] for p in w["passes"]]:
        entry = name.rsplit(".", 1)[0]
        assert (folder / name).read_bytes() == emit(entry, "essl")
        assert (folder / name).read_text().startswith("#version 300 es") and name in d["files"]
    material, descs = w["textures"]["material"], w["textures"]["descriptors"]
    words = (folder / "material.bin").stat().st_size // 4
    assert material["width"] * (material["height"] - 1) < words <= material["width"] * material["height"]
    assert descs["width"] * 4 == d["buffers"][1]["stride"] and descs["height"] == d["buffers"][1]["count"]
    for uniform in (material["uniform"], descs["uniform"], *w["inputs"]):
        assert f"usampler2D {uniform};" in (folder / "webgl_eval.frag").read_text() or \
               f"sampler2D {uniform};" in (folder / "webgl_eval.frag").read_text(), uniform
    assert "## WebGL2" in (folder / "INTEGRATION.md").read_text()
    assert "webgl2" not in exports["glsl"][1]


def test_slang_export_is_the_source(exports):
    from brdfz.gpu import slang

    folder, d = exports["slang"]
    assert d["functions"][0] == "float3 brdfz_eval(float3 wi, float3 wo)"
    ours = slang.compile_entry(folder / "shaders" / "kernels.slang", "brdfz_sample_kernel", "wgsl")
    theirs = slang.compile_entry(slang.SHADERS / "kernels.slang", "brdfz_sample_kernel", "wgsl")
    # The same code up to the file paths Slang writes into its output.
    assert ours.replace(os.fsencode(folder / "shaders"), b"").count(b"\n") == theirs.count(b"\n")
    assert not (folder / "shaders" / "check.slang").exists() and not (folder / "shaders" / "module.slang").exists()


def _pairs(n=4096, seed=3):
    from brdfz.gpu.check import pairs

    wi, wo = pairs(n, seed)
    u = np.random.default_rng(seed).random((n, 2)).astype(np.float32)
    return wi, wo, u


def _run_wgpu(folder, d, wi, wo, u):
    """A renderer's use of a WGSL export: only the exported files and brdfz.json."""
    wgpu = pytest.importorskip("wgpu")
    adapter = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
    if adapter is None:
        pytest.skip("wgpu found no adapter")
    device = adapter.request_device_sync()
    storage = wgpu.BufferUsage.STORAGE
    material = device.create_buffer_with_data(data=(folder / "material.bin").read_bytes(), usage=storage)
    descs = device.create_buffer_with_data(data=(folder / "descriptors.bin").read_bytes(), usage=storage)
    slot = {b["name"]: b["slot"] for b in d["buffers"]} | d["io_slots"]
    results = {}
    for k, (a, b, width) in zip(d["kernels"], [(wi, wo, 3), (wo, wi, 1), (wo, u, 7)]):
        module = device.create_shader_module(code=(folder / k["file"]).read_text())
        pipeline = device.create_compute_pipeline(layout="auto", compute={"module": module, "entry_point": k["entry"]})
        n = len(a)
        out = device.create_buffer(size=4 * n * width, usage=storage | wgpu.BufferUsage.COPY_SRC)
        buffers = {"material": material, "descriptors": descs,
                   "a": device.create_buffer_with_data(data=a.tobytes(), usage=storage),
                   "b": device.create_buffer_with_data(data=b.tobytes(), usage=storage), "out": out,
                   "count": device.create_buffer_with_data(data=np.array([n], np.uint32).tobytes(), usage=storage)}
        group = device.create_bind_group(layout=pipeline.get_bind_group_layout(0), entries=[
            {"binding": slot[name], "resource": {"buffer": buf}} for name, buf in buffers.items()])
        encoder = device.create_command_encoder()
        compute = encoder.begin_compute_pass()
        compute.set_pipeline(pipeline)
        compute.set_bind_group(0, group)
        compute.dispatch_workgroups((n + k["workgroup_size"][0] - 1) // k["workgroup_size"][0])
        compute.end()
        device.queue.submit([encoder.finish()])
        results[k["entry"]] = np.frombuffer(device.queue.read_buffer(out), np.float32)
    return results


def _run_gl(folder, d, wi, wo, u):
    """A renderer's use of a GLSL export on OpenGL 4.5: only the exported files and brdfz.json."""
    moderngl = pytest.importorskip("moderngl")
    try:
        ctx = moderngl.create_standalone_context(backend="egl", require=450)
    except Exception as e:  # moderngl raises plain Exceptions for a missing EGL or GL 4.5
        pytest.skip(f"no OpenGL 4.5 context: {e}")
    slot = {b["name"]: b["slot"] for b in d["buffers"]} | d["io_slots"]
    material = ctx.buffer((folder / "material.bin").read_bytes())
    descs = ctx.buffer((folder / "descriptors.bin").read_bytes())
    results = {}
    for k, (a, b, width) in zip(d["kernels"], [(wi, wo, 3), (wo, wi, 1), (wo, u, 7)]):
        shader = ctx.compute_shader((folder / k["file"]).read_text())
        n = len(a)
        buffers = {"material": material, "descriptors": descs, "a": ctx.buffer(a.tobytes()), "b": ctx.buffer(b.tobytes()),
                   "out": ctx.buffer(reserve=4 * n * width), "count": ctx.buffer(np.array([n], np.uint32).tobytes())}
        for name, buf in buffers.items():
            buf.bind_to_storage_buffer(slot[name])
        shader.run((n + 63) // 64)
        ctx.memory_barrier()
        results[k["entry"]] = np.frombuffer(buffers["out"].read(), np.float32).copy()
    return results


@pytest.mark.parametrize("target,backend", [("wgsl", "wgpu"), ("glsl", "gl")])
def test_exported_kernels_run_alone(exports, target, backend):
    """Bound by a renderer from the files alone, the kernels give the bits of brdfz.gpu's harness on the
    same driver, which test_gpu_shaders.py holds to the library; and eval agrees with the library."""
    brdfz = import_brdfz()
    from brdfz import gpu as brdfz_gpu
    from brdfz.gpu.check import relative_error

    folder, d = exports[target]
    wi, wo, u = _pairs()
    ours = (_run_wgpu if target == "wgsl" else _run_gl)(folder, d, wi, wo, u)
    try:
        harness = brdfz_gpu.backend(backend)
    except brdfz_gpu.BackendUnavailable as e:
        pytest.skip(f"the {backend} backend cannot start: {e}")
    layout = brdfz_gpu.Layout.from_export(folder)
    harness.bind(layout)
    assert np.array_equal(ours["brdfz_eval_kernel"].reshape(-1, 3), harness.eval(wi, wo))
    assert np.array_equal(ours["brdfz_pdf_kernel"], harness.pdf(wo, wi))
    s_wi, s_pdf, s_weight = harness.sample(wo, u)
    drawn = ours["brdfz_sample_kernel"].reshape(-1, 7)
    assert np.array_equal(drawn[:, :3], s_wi) and np.array_equal(drawn[:, 3], s_pdf)
    assert (drawn[:, 3] > 0).mean() > 0.99
    # The representation exported is the one the descriptor names: its library eval is what the GPU gives.
    built = brdfz.compress(brdfz.load(RGL), SPEC)
    err = relative_error(ours["brdfz_eval_kernel"].reshape(-1, 3), built.eval(wi.astype(np.float64), wo.astype(np.float64)))
    assert np.percentile(err, 99.9) < 1e-4, np.max(err)


def test_brdfz_file_records_its_error(cli, source, tmp_path):
    """A .brdfz exported as it is: the error it recorded when compress built it (over the grid)."""
    from brdfz.gpu import export

    brdfz = import_brdfz()
    stored = tmp_path / "m.brdfz"
    run(cli, "compress", RGL, "-o", stored, "--repr", SPEC)
    d = export(stored, tmp_path / "out", "wgsl")
    recorded = brdfz.container_metadata(stored)["achieved"]["metrics"]
    assert d["error"]["over"] == "grid" and d["error"]["cos_rmse_rel"] == recorded.cos_rmse_rel.mean
    assert d["source"] == "m.brdfz" and d["build_spec"] is None
    # A table has no recorded error unless a reference is named; with one it is measured.
    table = tmp_path / "t.binary"
    run(cli, "convert", RGL, table, "--res", "16x8x16")
    assert export(table, tmp_path / "t", "hlsl")["error"] is None
    assert export(table, tmp_path / "t", "hlsl", reference=RGL, error_pairs=512)["error"]["pairs"] == 512


def _env():
    env = dict(os.environ, BRDFZ_PYTHON_EXECUTABLE=sys.executable)
    import brdfz

    env["PYTHONPATH"] = os.pathsep.join([os.path.dirname(os.path.dirname(brdfz.__file__)), env.get("PYTHONPATH", "")])
    return env


def test_command_forwards_to_python(cli, source, tmp_path):
    out = tmp_path / "wgsl"
    p = subprocess.run([cli, "export", str(RGL), "-o", str(out), "--target", "wgsl", "--repr", SPEC], capture_output=True,
                       text=True, timeout=300, env=_env())
    assert p.returncode == 0, p.stderr
    assert f"wrote {out}: wgsl" in p.stdout and "cos_rmse_rel" in p.stdout
    assert json.loads((out / "brdfz.json").read_text())["build_spec"].startswith("svd:rank=10")


@pytest.mark.parametrize("case", ["missing input", "bad target", "bad spec", "no package", "no python"])
def test_bad_input_leaves_one_line_and_no_files(cli, source, tmp_path, case):
    out = tmp_path / "out"
    env = _env()
    args = [cli, "export", str(RGL), "-o", str(out), "--target", "wgsl"]
    if case == "missing input":
        args[2] = str(tmp_path / "nothing.bsdf")
    elif case == "bad target":
        args[-1] = "vulkan"
    elif case == "bad spec":
        args += ["--repr", "svd:rank=-3"]
    elif case == "no package":
        env["PYTHONPATH"] = str(tmp_path)
    else:
        env["BRDFZ_PYTHON_EXECUTABLE"] = str(tmp_path / "no-python")
    p = subprocess.run(args, capture_output=True, text=True, timeout=120, env=env, cwd=tmp_path)
    assert p.returncode == 1, (case, p.stdout, p.stderr)
    assert len(p.stderr.strip().splitlines()) == 1 and "Traceback" not in p.stderr, p.stderr
    assert not out.exists() or not any(out.rglob("*")), list(out.rglob("*"))
    if case == "no package":
        assert "needs the brdfz Python package" in p.stderr
