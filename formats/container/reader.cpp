#include <algorithm>
#include <tuple>

#include "brdfz/errors.h"
#include "storage.h"

namespace brdfz::container {
namespace {

std::string feature_list(const std::vector<Feature>& fs) {
    std::string s;
    for (const Feature& f : fs) s += (s.empty() ? "" : ", ") + f.name;
    return s;
}

// The file must be a brdfz container, and this library must know every feature it uses.
Metadata read_header(const h5::ReadNode& root) {
    const std::string& path = root.file();
    if (!root.has_attr("format") || root.str("format") != "brdfz")
        throw FormatError(path, "not a .brdfz container (an HDF5 file without format = \"brdfz\")");
    Metadata m;
    const std::uint64_t version = root.u64("version"), min_reader = root.u64("min_reader_version");
    if (version == 0 || version > 0xFFFFFFFFu || min_reader == 0 || min_reader > version)
        throw FormatError(path, "invalid container version " + std::to_string(version) + " (min reader version " +
                                    std::to_string(min_reader) + ")");
    m.version = static_cast<std::uint32_t>(version);
    m.min_reader_version = static_cast<std::uint32_t>(min_reader);
    const std::vector<std::string> names = root.strs("features");
    const std::vector<std::uint64_t> since = root.u64s("feature_versions");
    if (names.size() != since.size())
        throw FormatError(path, "attributes 'features' and 'feature_versions' differ in length");
    for (std::size_t k = 0; k < names.size(); ++k) {
        if (since[k] == 0 || since[k] > version)
            throw FormatError(path, "feature '" + names[k] + "' has an invalid version " + std::to_string(since[k]));
        m.features.push_back({names[k], static_cast<std::uint32_t>(since[k])});
    }

    const std::vector<Feature> known = known_features();
    for (const Feature& f : m.features)
        if (std::find(known.begin(), known.end(), f) == known.end())
            throw UnsupportedError(path, "needs container feature '" + f.name + "' (container version " +
                                             std::to_string(f.since) + "), which this brdfz does not know; it reads "
                                             "container version " + std::to_string(kVersion) + " with features " +
                                             feature_list(known) + " (a newer brdfz is needed)");
    if (m.min_reader_version > kVersion)
        throw UnsupportedError(path, "needs a reader of container version " + std::to_string(m.min_reader_version) +
                                         "; this brdfz reads version " + std::to_string(kVersion));
    return m;
}

PerChannel read_metric(const h5::ReadNode& node, const char* name) {
    const std::vector<double> v = node.f64s(name);
    if (v.size() != 4) throw FormatError(node.file(), node.path() + ": attribute '" + name + "' is not 4 values");
    return {v[0], v[1], v[2], v[3]};
}

void read_rest(const h5::ReadNode& root, Metadata& m) {
    m.library_version = root.str("library_version");
    m.created = root.str("created");
    m.source = {root.str("source_file"), root.str("source_format"), root.str("source_sha256")};
    m.units = root.str("units");
    m.cosine = root.str("cosine");
    m.conventions = root.str("conventions");
    // Values in other units, with the cosine, or in another frame would be read as if they were not.
    for (const auto& [name, value, expected] : {std::tuple{"units", &m.units, detail::kUnits},
                                                std::tuple{"cosine", &m.cosine, detail::kCosine},
                                                std::tuple{"conventions", &m.conventions, detail::kConventions}})
        if (*value != expected)
            throw UnsupportedError(root.file(), std::string("attribute '") + name + "' is \"" + *value +
                                                    "\"; this brdfz reads only \"" + expected + "\"");

    const h5::ReadNode ach = root.group("achieved");
    Achieved& a = m.achieved;
    a.lossless = ach.u64("lossless") != 0;
    a.nbytes = ach.u64("nbytes");
    const std::vector<std::uint64_t> c = ach.u64s("counts");
    if (c.size() != 6) throw FormatError(root.file(), "/achieved: attribute 'counts' is not 6 values");
    a.counts = {c[0], c[1], c[2], c[3], c[4], c[5]};
    if (ach.has_attr("cos_rmse")) {
        Metrics x;
        x.cos_rmse = read_metric(ach, "cos_rmse");
        x.cos_rmse_rel = read_metric(ach, "cos_rmse_rel");
        x.log_rmse = read_metric(ach, "log_rmse");
        x.cbrt_rmse = read_metric(ach, "cbrt_rmse");
        x.samples = ach.u64("metric_samples");
        x.negatives = ach.u64("metric_negatives");
        a.metrics = x;
    }
}

void read_representation_attrs(const h5::ReadNode& rep, Metadata& m) {
    m.representation = rep.str("type");
    m.spec = rep.str("spec");
    if (rep.has_attr("build_spec")) m.build_spec = rep.str("build_spec");
}

}  // namespace

ReadResult read(const std::string& path, Lookup lookup) {
    const h5::Reader reader(path);
    const h5::ReadNode root = reader.root();
    ReadResult out;
    out.meta = read_header(root);
    read_rest(root, out.meta);
    const h5::ReadNode rep = root.group("representation");
    read_representation_attrs(rep, out.meta);
    const detail::StorageModule* module = detail::find_storage(out.meta.representation);
    if (!module) throw FormatError(path, "/representation: unknown type '" + out.meta.representation + "'");
    out.brdf = module->read(rep, detail::ReadContext{lookup});
    return out;
}

Metadata read_metadata(const std::string& path) {
    const h5::Reader reader(path);
    const h5::ReadNode root = reader.root();
    Metadata m = read_header(root);
    read_rest(root, m);
    const h5::ReadNode rep = root.group("representation");
    read_representation_attrs(rep, m);
    for (const std::string& name : rep.datasets()) {
        const h5::Dataset d = rep.dataset(name);
        m.datasets.push_back({d.path(), h5::dtype_name(d.type()), d.shape(), d.stored_crc()});
    }
    return m;
}

}  // namespace brdfz::container
