"""A .brdfzrt file (formats/SPEC.md §6) as the shaders read it: its bytes as they are (then float
copies of its float64 arrays), and a descriptor per object (bindings/gpu/shaders/desc.slang's
BrdfzDesc: section offsets and small parameters, read from the section table). The C++ reader checks
the file (brdfz.load does); this reads only what the descriptors need."""

import re
import struct
from pathlib import Path

import numpy as np

from .slang import SHADERS

MAGIC = b"\x89BZRT\r\n\x1a"
KIND_NAMES = {1: "table", 2: "factorisation", 3: "analytic", 4: "φh stack"}
GPU_KINDS = (1, 2, 3, 4)

# Lobe families by their id (the order of lib/runtime/include/brdfz/runtime/kernels/lobes/families.h)
# and their parameter counts: every family, as lobes.slang has them.
LOBE_FAMILIES = {"lambert": (0, 3), "blinn_phong": (1, 4), "ward": (2, 4), "lafortune": (14, 6), "ggx": (3, 5), "ggx_dielectric": (4, 5), "ggx_conductor": (5, 10),
                 "ggx_sep": (6, 5), "ggx_dielectric_sep": (7, 5), "ggx_conductor_sep": (8, 10), "beckmann": (9, 5),
                 "beckmann_dielectric": (10, 5), "beckmann_conductor": (11, 10), "ggx_aniso": (12, 6), "ashikhmin_shirley": (13, 8)}
ALBEDO_NODES = 16


def _tag(s: str) -> int:
    return int.from_bytes(s.encode(), "little")


def desc_dtype() -> np.dtype:
    """BrdfzDesc's fields in order, from the shader source itself (one definition): 4-byte scalars
    only, so that std430, HLSL's, WGSL's and Metal's layouts are all the packed one."""
    text = (SHADERS / "desc.slang").read_text()
    body = re.search(r"struct BrdfzDesc \{(.*?)\};", text, re.S).group(1)
    types = {"uint": "<u4", "int": "<i4", "float": "<f4"}
    fields = []
    for line in body.split("\n"):
        m = re.match(r"\s*(uint|int|float)\s+([^;]+);", line)
        if m:
            fields += [(name.strip(), types[m.group(1)]) for name in m.group(2).split(",")]
    return np.dtype(fields)


class Layout:
    """The file's bytes (padded to a multiple of 4 for 32-bit reads) and its descriptors."""

    def __init__(self, path):
        self.path = Path(path)
        data = self.path.read_bytes()
        if len(data) < 64 or data[:8] != MAGIC:
            raise ValueError(f"{path}: not a brdfz runtime layout")
        version, _, size, count, _, kind, _ = struct.unpack_from("<IIQIIII", data, 8)
        if version not in (1, 2):
            raise ValueError(f"{path}: runtime layout version {version} (this reads 1 and 2)")
        self.kind = kind
        if kind not in GPU_KINDS:
            raise ValueError(f"{self.path}: the GPU shaders do not evaluate {KIND_NAMES.get(kind, kind)} layouts")
        if 64 + 32 * count > len(data):
            raise ValueError(f"{path}: truncated ({len(data)} bytes hold no table of {count} sections)")
        objects = {}
        for i in range(count):
            tag, dtype, offset, n, obj = struct.unpack_from("<IIQQI", data, 64 + 32 * i)
            objects.setdefault(obj, {})[tag] = (dtype, offset, n)
        self.data = data + b"\0" * (-len(data) % 4)
        # One descriptor per object: the root, then a φh stack's slices in order.
        self.desc = np.concatenate([self._descriptor(objects[k]) for k in sorted(objects)])

    @classmethod
    def from_export(cls, folder):
        """The buffers `brdfz export --target` wrote into `folder` (material.bin, descriptors.bin), as the
        backends bind them."""
        folder = Path(folder)
        layout = cls.__new__(cls)
        layout.path = folder / "material.bin"
        layout.data = layout.path.read_bytes()
        layout.desc = np.frombuffer((folder / "descriptors.bin").read_bytes(), desc_dtype()).copy()
        if len(layout.data) % 4 or len(layout.data) < 64 or layout.data[:8] != MAGIC or len(layout.desc) == 0:
            raise ValueError(f"{folder}: not a brdfz GPU export")
        layout.kind = int(layout.desc["kind"][0])
        return layout

    def _append(self, array) -> int:
        """Appends 32-bit words to the bytes the shaders read; returns their byte offset."""
        offset = len(self.data)
        self.data += np.ascontiguousarray(array).tobytes()
        return offset

    def _find(self, tag):
        return self.sections.get(_tag(tag))

    def _offset(self, tag):
        s = self._find(tag)
        if s is None:
            raise ValueError(f"{self.path}: an object has no {tag} section")
        return s[1]

    def _array(self, tag, dtype):
        s = self._find(tag)
        if s is None:
            raise ValueError(f"{self.path}: an object has no {tag} section")
        return np.frombuffer(self.data, dtype=dtype, count=s[2], offset=s[1])

    def _descriptor(self, sections) -> np.ndarray:
        """One object's descriptor, from its sections."""
        self.sections = sections
        d = np.zeros(1, desc_dtype())
        kind = int(self._array("KIND", "<i4")[0])
        d["kind"] = kind
        if self._find("SAMP"):
            self._sampler(d)
        if kind == 3:
            return self._lobes(d)
        if kind == 4:
            symmetry, slices = self._array("PHIH", "<i4")
            d["phi_h_bilateral"], d["phi_h_slices"] = symmetry == 2, slices
            return d
        grid = self._array("GRID", "<i4")
        for name, v in zip(("n_theta_h", "n_theta_d", "n_phi_d", "centre", "phi_d_axis", "lookup"), grid):
            d[name] = v
        d["theta_d_warp"] = self._array("WARP", "<f8")[0] if self._find("WARP") else 0.0
        d["theta_h_warp"] = self._array("HWRP", "<f8")[0] if self._find("HWRP") else 0.0
        if kind == 1:
            if self._find("VF32"):
                d["dtype"], d["values"] = 0, self._offset("VF32")
            elif self._find("VF16"):
                d["dtype"], d["values"], d["decode"] = 1, self._offset("VF16"), self._offset("SC16")
            else:
                d["dtype"], d["values"], d["decode"] = 2, self._offset("VU8L"), self._offset("LUT8")
        else:
            layout, space, colour, rank = self._array("FPAR", "<i4")
            d["layout"], d["space"], d["shared_colour"], d["rank"] = layout, space, colour, rank
            d["factor_u"], d["factor_v"] = self._offset("FACU"), self._offset("FACV")
            d["factor_u_f16"] = self._find("FACU")[0] == 5
            d["factor_v_f16"] = self._find("FACV")[0] == 5
            if colour == 1:
                d["factor_colour"] = self._offset("FCOL")
            # The ceiling in the transform space, as the C++ reader computes it (in double, then float).
            top = np.minimum(self._array("FMAX", "<f4").astype(np.float64), np.finfo(np.float32).max)
            ceiling = np.log1p(top) if space == 2 else np.cbrt(top) if space == 3 else top
            d["ceiling_r"], d["ceiling_g"], d["ceiling_b"] = ceiling.astype(np.float32)
        return d

    def _sampler(self, d):
        """The compact sampler's sections: every table and factorisation has one, an analytic model
        may (else its lobes' mixture draws)."""
        slices, rows, cols = self._array("SAMP", "<i4")
        d["slices"], d["rows"], d["cols"] = slices, rows, cols
        d["cos_theta_max"], d["cosine_share"] = self._array("SPRM", "<f8")
        d["s_edges"], d["row_cdf"] = self._offset("SEDG"), self._offset("SROW")
        d["col_cdf"], d["edge_weight"] = self._offset("SCOL"), self._offset("SEWT")

    def _lobes(self, d) -> np.ndarray:
        model = bytes(self._array("MODL", "u1")).decode()
        terms = []
        first = 0
        for term in model.split("+"):
            # Trailing digits repeat a lobe ("lafortune3": three), as model strings allow.
            name, repeat = re.fullmatch(r"(.*?)(\d*)", term).groups()
            if name not in LOBE_FAMILIES:
                raise ValueError(f"{self.path}: unknown lobe family '{name}' (the shaders have {', '.join(LOBE_FAMILIES)})")
            family, count = LOBE_FAMILIES[name]
            for _ in range(int(repeat or 1)):
                terms.append((family, first))
                first += count
        params = self._array("PRMS", "<f8")
        if len(params) != first:
            raise ValueError(f"{self.path}: PRMS does not fit the model '{model}'")
        d["lobe_count"] = len(terms)
        d["lobe_terms"] = self._append(np.array(terms, "<u4"))
        d["lobe_params"] = self._append(params.astype("<f4"))
        if not self._find("SAMP"):
            albedo = self._array("ALBD", "<f8")
            if len(albedo) != ALBEDO_NODES * len(terms):
                raise ValueError(f"{self.path}: ALBD does not fit the model '{model}'")
            d["lobe_albedo"] = self._append(albedo.astype("<f4"))
        return d
