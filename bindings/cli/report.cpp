#include "report.h"

#include <array>
#include <cstdio>
#include <numbers>

#include "brdfz/albedo.h"
#include "output.h"

namespace brdfz::cli {
namespace {

std::string fixed(double v, const char* fmt = "%.6g") {
    char buf[48];
    std::snprintf(buf, sizeof buf, fmt, v);
    return buf;
}

// Tables hold f_r in 1/sr; RGL files their own units; analytic models parameters.
std::string range_text(const SourceInfo& info) {
    if (!info.has_range) return "- (nothing stored is a value of f_r)";
    const std::string range = "[" + fixed(info.min_value) + ", " + fixed(info.max_value) + "]";
    if (info.dims_of == "parameters") return range + " (parameter values)";
    if (info.format == "rgl" || info.dims_of.rfind("rgb tensor", 0) == 0) return range + " (stored values)";
    return range + " 1/sr";
}


// Container metadata (formats/SPEC.md): provenance, conventions, versions, achieved figures, datasets.
void container_json(JsonWriter& j, const container::Metadata& m) {
    j.key("container").begin_object();
    j.key("version").value(std::size_t{m.version});
    j.key("min_reader_version").value(std::size_t{m.min_reader_version});
    j.key("features").begin_array();
    for (const container::Feature& f : m.features) j.value(f.name + "@" + std::to_string(f.since));
    j.end_array();
    j.key("library_version").value(m.library_version);
    j.key("created").value(m.created);
    j.key("source").begin_object();
    j.key("file").value(m.source.file).key("format").value(m.source.format).key("sha256").value(m.source.sha256);
    j.end_object();
    j.key("units").value(m.units).key("cosine").value(m.cosine).key("conventions").value(m.conventions);
    j.key("representation").value(m.representation).key("spec").value(m.spec);
    if (!m.build_spec.empty()) j.key("build_spec").value(m.build_spec);
    j.key("achieved").begin_object();
    j.key("lossless").value(m.achieved.lossless).key("nbytes").value(std::size_t{m.achieved.nbytes});
    if (m.achieved.metrics) {
        const Metrics& x = *m.achieved.metrics;
        j.key("cos_rmse").value(x.cos_rmse.mean).key("cos_rmse_rel").value(x.cos_rmse_rel.mean);
        j.key("log_rmse").value(x.log_rmse.mean).key("cbrt_rmse").value(x.cbrt_rmse.mean);
    }
    j.end_object();
    j.key("datasets").begin_array();
    for (const container::DatasetInfo& d : m.datasets) {
        j.begin_object().key("path").value(d.path).key("dtype").value(d.dtype).key("shape").begin_array();
        for (std::uint64_t s : d.shape) j.value(std::size_t{s});
        char crc[16];
        std::snprintf(crc, sizeof crc, "%08x", d.crc32c);
        j.end_array().key("crc32c").value(std::string(crc)).end_object();
    }
    j.end_array();
    j.end_object();
}

void container_text(const container::Metadata& m, std::ostream& os) {
    os << "  container  version " << m.version << " (readers >= " << m.min_reader_version << "), features";
    for (std::size_t k = 0; k < m.features.size(); ++k) os << (k ? ", " : " ") << m.features[k].name;
    os << "\n  written    " << m.created << " by brdfz " << m.library_version << "\n  source     ";
    if (m.source.file.empty())
        os << "(not recorded)\n";
    else
        os << m.source.file << " (" << m.source.format << ")\n";
    if (!m.source.sha256.empty()) os << "  sha256     " << m.source.sha256 << "\n";
    os << "  values     " << m.units << ", cosine " << m.cosine << "; " << m.conventions << "\n"
       << "  stores     " << m.representation << ": " << m.spec << "\n";
    if (!m.build_spec.empty()) os << "  built by   brdfz compress --repr " << m.build_spec << "\n";
    os
       << "  achieved   " << (m.achieved.lossless ? "stored as given" : "tabulated") << ", " << m.achieved.nbytes << " bytes";
    if (m.achieved.metrics)
        os << ", cos_rmse " << fixed(m.achieved.metrics->cos_rmse.mean) << ", cos_rmse_rel "
           << fixed(m.achieved.metrics->cos_rmse_rel.mean) << " against the source";
    os << "\n";
    for (const container::DatasetInfo& d : m.datasets) {
        os << "  dataset    " << d.path << "  " << d.dtype << " ";
        for (std::size_t k = 0; k < d.shape.size(); ++k) os << (k ? "x" : "") << d.shape[k];
        char crc[16];
        std::snprintf(crc, sizeof crc, "%08x", d.crc32c);
        os << "  crc32c " << crc << "\n";
    }
}

}  // namespace

void write_source_keys(JsonWriter& j, const std::string& path, const SourceInfo& info) {
    j.key("file").value(path);
    j.key("format").value(info.format);
    j.key("dims").begin_array();
    for (std::size_t d : info.dims) j.value(d);
    j.end_array();
    j.key("dims_of").value(info.dims_of);
    j.key("valid").value(info.counts.valid);
    j.key("negative").value(info.counts.negative);
    j.key("nan").value(info.counts.nan);
    j.key("inf").value(info.counts.inf);
    if (info.format == "rgl") j.key("luminance_negative").value(info.luminance_negative);
}

void print_source_lines(std::ostream& os, const std::string& path, const SourceInfo& info, const std::string& describe,
                        std::size_t nbytes, const SourceNotes& notes) {
    std::string dims;
    for (std::size_t d : info.dims) dims += (dims.empty() ? "" : "x") + std::to_string(d);
    os << path << "\n"
       << "  format     " << info.format << "\n"
       << "  dims       " << dims << (notes.dims.empty() && !info.dims_of.empty() ? " (" + info.dims_of + ")" : notes.dims)
       << "\n"
       << "  stored as  " << describe << "\n"
       << "  nbytes     " << nbytes << "\n"
       << "  valid      " << info.counts.valid << "\n"
       << "  negative   " << info.counts.negative << notes.negative << "\n"
       << "  nan        " << info.counts.nan << notes.nan << "\n"
       << "  inf        " << info.counts.inf << notes.inf << "\n";
    if (info.luminance_negative > 0)
        os << "  luminance  " << info.luminance_negative << " negative values (the sampling density), taken as 0\n";
}

void print_info(const std::string& path, const Loaded& loaded, bool json, std::ostream& os,
                const container::Metadata* container) {
    const SourceInfo& info = loaded.info;
    Rgb albedo[std::size(kAlbedoAnglesDeg)];
    SampledAlbedo sampled[std::size(kAlbedoAnglesDeg)];
    for (std::size_t k = 0; k < std::size(kAlbedoAnglesDeg); ++k) {
        const double theta_o = kAlbedoAnglesDeg[k] * std::numbers::pi / 180.0;
        albedo[k] = directional_albedo(*loaded.brdf, theta_o);
        sampled[k] = sampled_albedo(*loaded.brdf, theta_o, kAlbedoSamples);
    }
    const Metrics reciprocity = reciprocity_error(*loaded.brdf);

    if (json) {
        JsonWriter j(os);
        j.begin_object();
        write_source_keys(j, path, info);
        j.key("min").value(info.min_value);
        j.key("max").value(info.max_value);
        j.key("range_stored").value(info.has_range);
        j.key("nbytes").value(loaded.brdf->nbytes());
        j.key("channels").value(static_cast<std::size_t>(loaded.brdf->channels()));
        j.key("describe").value(loaded.brdf->describe());
        j.key("albedo").begin_array();
        for (std::size_t k = 0; k < std::size(kAlbedoAnglesDeg); ++k) {
            j.begin_object();
            j.key("theta_o_deg").value(kAlbedoAnglesDeg[k]);
            j.key("r").value(albedo[k][0]).key("g").value(albedo[k][1]).key("b").value(albedo[k][2]);
            j.key("sampled").begin_object();
            for (int c = 0; c < 3; ++c) j.key(std::string(1, "rgb"[c])).value(sampled[k].mean[c]);
            for (int c = 0; c < 3; ++c) j.key(std::string("stderr_") + "rgb"[c]).value(sampled[k].stderr_[c]);
            j.end_object();
            j.end_object();
        }
        j.end_array();
        j.key("reciprocity_error").value(reciprocity.cos_rmse_rel.mean);
        if (container) container_json(j, *container);
        j.end_object();
        os << "\n";
        return;
    }
    print_source_lines(os, path, info, loaded.brdf->describe(), loaded.brdf->nbytes());
    os << "  range      " << range_text(info) << "\n"
       << "  albedo     theta_o      r        g        b         sampled (" << kAlbedoSamples
       << " samples)  r, g, b ± stderr\n";
    for (std::size_t k = 0; k < std::size(kAlbedoAnglesDeg); ++k) {
        os << "             " << fixed(kAlbedoAnglesDeg[k], "%5.0f") << " deg  " << fixed(albedo[k][0], "%.4f") << "   "
           << fixed(albedo[k][1], "%.4f") << "   " << fixed(albedo[k][2], "%.4f") << "    ";
        for (int c = 0; c < 3; ++c)
            os << fixed(sampled[k].mean[c], "%.4f") << "±" << fixed(sampled[k].stderr_[c], "%.4f") << (c < 2 ? "  " : "\n");
    }
    os << "  reciprocity error " << fixed(reciprocity.cos_rmse_rel.mean, "%.4g")
       << " (cos_rmse_rel of f(wo, wi) against f(wi, wo) over " << reciprocity.samples << " direction pairs)\n";
    if (container) container_text(*container, os);
}

namespace {
std::array<std::pair<const char*, const PerChannel*>, 4> metric_rows(const Metrics& m) {
    return {{{"cos_rmse", &m.cos_rmse}, {"cos_rmse_rel", &m.cos_rmse_rel}, {"log_rmse", &m.log_rmse}, {"cbrt_rmse", &m.cbrt_rmse}}};
}
}  // namespace

void write_metrics(JsonWriter& j, const Metrics& m) {
    j.begin_object();
    for (const auto& [name, v] : metric_rows(m)) {
        j.key(name).begin_object();
        j.key("r").value(v->r).key("g").value(v->g).key("b").value(v->b).key("mean").value(v->mean);
        j.end_object();
    }
    j.key("samples").value(m.samples);
    j.key("negatives").value(m.negatives);
    j.end_object();
}

void print_metrics(const Metrics& m, bool json, std::ostream& os, Over over) {
    if (json) {
        JsonWriter j(os);
        write_metrics(j, m);
        os << "\n";
        return;
    }
    const auto rows = metric_rows(m);
    os << "  metric         r            g            b            mean\n";
    for (const auto& [name, v] : rows) {
        char buf[128];
        std::snprintf(buf, sizeof buf, "  %-13s  %-11.5g  %-11.5g  %-11.5g  %.5g\n", name, v->r, v->g, v->b, v->mean);
        os << buf;
    }
    os << "  over " << m.samples
       << (over == Over::Grid ? " bins (theta_i, theta_o < cut-off)" : " direction pairs (uniform in solid angle)");
    if (m.negatives) os << "; " << m.negatives << " negative values taken as 0";
    os << "\n";
}

}  // namespace brdfz::cli
