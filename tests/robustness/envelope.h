// Hostile payloads in valid envelopes, for the robustness tests and the payload fuzz harnesses: a
// .brdfz container whose brdfz header, structure CRC and per-dataset CRC-32C are all correct (written
// by the container's own low-level writer) around whatever /representation group the caller fills
// in, so that only the readers' checks of the values stand between them and evaluation.
#pragma once

#include <bit>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include <cstdio>
#include <cstring>
#include <fstream>

#include "brdfz/formats/container.h"
#include "brdfz/formats/rgl.h"
#include "container/checksum.h"
#include "container/h5.h"
#include "container/storage.h"

namespace brdfz::test {

// What the root's units, cosine and conventions attributes say: the library's own by default.
struct Meaning {
    std::string units = container::detail::kUnits, cosine = container::detail::kCosine,
                conventions = container::detail::kConventions;
};

// Root attributes of a current container listing every known feature, an /achieved group, and a
// /representation group of `type` that fill(WriteNode&) completes.
template <typename Fill>
void write_envelope(const std::string& path, const std::string& type, Fill fill, const Meaning& meaning = {}) {
    container::h5::Writer w(path);
    {
        container::h5::WriteNode root = w.root();
        std::vector<std::string> names;
        std::vector<std::uint64_t> since;
        for (const container::Feature& f : container::known_features()) {
            names.push_back(f.name);
            since.push_back(f.since);
        }
        root.attr("format", std::string("brdfz"));
        root.attr("version", std::uint64_t{container::kVersion});
        root.attr("min_reader_version", std::uint64_t{1});
        root.attr("features", std::span<const std::string>(names));
        root.attr("feature_versions", std::span<const std::uint64_t>(since));
        for (const char* a : {"library_version", "created", "source_file", "source_format", "source_sha256"})
            root.attr(a, std::string("x"));
        root.attr("units", meaning.units);
        root.attr("cosine", meaning.cosine);
        root.attr("conventions", meaning.conventions);
        container::h5::WriteNode ach = root.group("achieved");
        ach.attr("lossless", std::uint64_t{1});
        ach.attr("nbytes", std::uint64_t{8});
        const std::vector<std::uint64_t> counts(6, 0);
        ach.attr("counts", std::span<const std::uint64_t>(counts));
        container::h5::WriteNode rep = root.group("representation");
        rep.attr("type", type);
        rep.attr("spec", std::string("hostile payload"));
        fill(rep);
    }
    w.close();
}

// The grid attributes every gridded module reads.
inline void grid_attrs(container::h5::WriteNode& rep, std::uint64_t nh, std::uint64_t nd, std::uint64_t np) {
    const std::uint64_t dims[3] = {nh, nd, np};
    rep.attr("grid", std::span<const std::uint64_t>(dims));
    rep.attr("bin_position", std::string("centre"));
    rep.attr("theta_h_axis", std::string("sqrt"));
}

// A float32 table of nh x nd x np bins holding `values` (3 per bin).
inline void write_float32_table(const std::string& path, std::uint64_t nh, std::uint64_t nd, std::uint64_t np,
                                const std::vector<float>& values, const Meaning& meaning = {}) {
    write_envelope(
        path, "tabular",
        [&](container::h5::WriteNode& rep) {
            grid_attrs(rep, nh, nd, np);
            rep.attr("dtype", std::string("float32"));
            rep.attr("invalid", std::string("nan"));
            rep.dataset("values", container::h5::DType::F32, {nh, nd, np, 3}, values.data());
        },
        meaning);
}

// SVD factors (log space, layout h_dp, separate colour, float32) of rank 1 on nh x nd x np:
// u [nh, 3], v [nd * np, 3].
inline void write_factors(const std::string& path, std::uint64_t nh, std::uint64_t nd, std::uint64_t np,
                          const std::vector<float>& u, const std::vector<float>& v) {
    write_envelope(path, "factored", [&](container::h5::WriteNode& rep) {
        grid_attrs(rep, nh, nd, np);
        rep.attr("method", std::string("svd"));
        rep.attr("space", std::string("log"));
        rep.attr("layout", std::string("h_dp"));
        rep.attr("colour", std::string("separate"));
        rep.attr("rank", std::uint64_t{1});
        rep.attr("dtype", std::string("float32"));
        rep.dataset("u", container::h5::DType::F32, {nh, 3}, u.data());
        rep.dataset("v", container::h5::DType::F32, {nd * np, 3}, v.data());
    });
}

// An analytic model and its float64 parameters (names as the model lists them).
inline void write_analytic(const std::string& path, const std::string& model, const std::vector<std::string>& names,
                           const std::vector<double>& params) {
    write_envelope(path, "analytic", [&](container::h5::WriteNode& rep) {
        rep.attr("model", model);
        rep.attr("param_names", std::span<const std::string>(names));
        rep.dataset("params", container::h5::DType::F64, {params.size()}, params.data());
    });
}

// The parts of a PCA material with its basis embedded (formats/SPEC.md, "pca"), on an nh x nd x np
// grid with centre bins: median and mean of 3 values per bin, components [k_max, bins, 3], variances
// [k_max], k coefficients. The basis's content hash is computed as the spec defines it, so that it
// matches whatever the values are.
struct PcaParts {
    std::uint64_t nh = 0, nd = 0, np = 0;
    double epsilon = 1e-3;
    std::vector<float> median, mean, components, coefficients;
    std::vector<double> variances;
};

inline void write_pca(const std::string& path, const PcaParts& p) {
    char record[256];
    std::snprintf(record, sizeof record,
                  "brdfz pca basis 1\ngrid %llux%llux%llu centre\ntransform log-cosine-median %.17g\nk_max %zu\n",
                  static_cast<unsigned long long>(p.nh), static_cast<unsigned long long>(p.nd),
                  static_cast<unsigned long long>(p.np), p.epsilon, p.variances.size());
    static_assert(std::endian::native == std::endian::little, "the hash covers little-endian values");
    container::Sha256 h;
    h.update(record, std::strlen(record));
    for (const std::vector<float>* part : {&p.median, &p.mean, &p.components})
        h.update(part->data(), part->size() * sizeof(float));
    h.update(p.variances.data(), p.variances.size() * sizeof(double));
    const std::string hash = container::hex(h.finish());
    write_envelope(path, "pca", [&](container::h5::WriteNode& rep) {
        grid_attrs(rep, p.nh, p.nd, p.np);
        const std::uint64_t k_max = p.variances.size();
        const std::vector<std::uint64_t> table{p.nh, p.nd, p.np, 3};
        rep.attr("transform", std::string("log-cosine-median"));
        rep.attr("epsilon", p.epsilon);
        rep.attr("k", std::uint64_t{p.coefficients.size()});
        rep.attr("k_max", k_max);
        rep.attr("basis_storage", std::string("embedded"));
        rep.attr("basis_sha256", hash);
        if (!p.coefficients.empty())
            rep.dataset("coefficients", container::h5::DType::F32, {p.coefficients.size()}, p.coefficients.data());
        rep.dataset("median", container::h5::DType::F32, table, p.median.data());
        rep.dataset("mean", container::h5::DType::F32, table, p.mean.data());
        rep.dataset("components", container::h5::DType::F32, {k_max, p.nh, p.nd, p.np, 3}, p.components.data());
        rep.dataset("variances", container::h5::DType::F64, {k_max}, p.variances.data());
    });
}

// RGL tensors as the container's RGL storage stores them (formats/container/rgl.cpp), unchecked.
inline void write_rgl_container(const std::string& path, const rgl::Tensors& t) {
    write_envelope(path, "rgl", [&](container::h5::WriteNode& rep) {
        const std::uint64_t n = t.theta_i.size();
        const auto grids = [&](const char* name, const rgl::Grids& g, std::vector<std::uint64_t> shape) {
            shape.push_back(g.rows);
            shape.push_back(g.cols);
            rep.dataset(name, container::h5::DType::F32, shape, g.values.data());
        };
        rep.attr("jacobian", std::uint64_t{t.jacobian});
        rep.dataset("theta_i", container::h5::DType::F32, {n}, t.theta_i.data());
        grids("ndf", t.ndf, {});
        grids("sigma", t.sigma, {});
        grids("vndf", t.vndf, {n});
        grids("rgb", t.rgb, {n, 3});
        if (!t.luminance.values.empty()) grids("luminance", t.luminance, {n});
    });
}

// RGL tensors as an isotropic RGB .bsdf (tensor_file 1.0 with the fields Mitsuba's `measured` reads),
// unchecked: the tests' own writer, since the library's writes only what RglBrdf accepts.
inline void write_bsdf(const std::string& path, const rgl::Tensors& t) {
    struct Field {
        std::string name;
        std::uint8_t dtype;  // 1 uint8, 10 float32
        std::vector<std::uint64_t> shape;
        std::string bytes;
    };
    const auto f32 = [](const char* name, std::vector<std::uint64_t> shape, const std::vector<float>& v) {
        return Field{name, 10, std::move(shape), std::string(reinterpret_cast<const char*>(v.data()), 4 * v.size())};
    };
    const std::uint64_t n = t.theta_i.size(), rows = t.rgb.rows, cols = t.rgb.cols;
    const std::vector<float> phi_i{0.0f};
    const std::vector<Field> fields{
        {"description", 1, {4}, "test"},
        f32("phi_i", {1}, phi_i),
        f32("theta_i", {n}, t.theta_i),
        f32("sigma", {t.sigma.rows, t.sigma.cols}, t.sigma.values),
        f32("ndf", {t.ndf.rows, t.ndf.cols}, t.ndf.values),
        f32("vndf", {1, n, t.vndf.rows, t.vndf.cols}, t.vndf.values),
        f32("luminance", {1, n, rows, cols}, t.luminance.values),
        f32("rgb", {1, n, 3, rows, cols}, t.rgb.values),
        {"jacobian", 1, {1}, std::string(1, t.jacobian ? '\1' : '\0')},
    };
    static_assert(std::endian::native == std::endian::little, "tensor_file is little-endian");
    std::string header("tensor_file\0\1\0", 14);
    const auto put = [&](auto v) { header.append(reinterpret_cast<const char*>(&v), sizeof v); };
    put(static_cast<std::uint32_t>(fields.size()));
    std::uint64_t offset = header.size();
    for (const Field& f : fields) offset += 2 + f.name.size() + 2 + 1 + 8 + 8 * f.shape.size();
    for (const Field& f : fields) {
        put(static_cast<std::uint16_t>(f.name.size()));
        header += f.name;
        put(static_cast<std::uint16_t>(f.shape.size()));
        put(f.dtype);
        put(offset);
        for (std::uint64_t d : f.shape) put(d);
        offset += f.bytes.size();
    }
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out << header;
    for (const Field& f : fields) out << f.bytes;
}

}  // namespace brdfz::test
