// PCA storage (brdfz/repr/pca.h): a material's k coefficients, with its basis either embedded (the
// basis's arrays as datasets in /representation) or referenced (a file name resolved against the
// material's directory, and the basis's content hash, checked when the basis is read). A basis file
// is a material with k = 0 and the basis embedded. formats/SPEC.md, "pca".
#include <bit>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <sys/stat.h>

#include "brdfz/errors.h"
#include "brdfz/formats/pca_basis.h"
#include "container/checksum.h"
#include "container/sampler.h"
#include "container/storage.h"
#include "detail/bytes.h"
#include "detail/table_io.h"

namespace brdfz::container {
namespace detail {
namespace {

const Feature kPca{"pca", 2};
const Feature kPcaExternal{"pca.external-basis", 2};
const Feature kFullPhiD{"pca.full-phi-d", 3};
// The name of the mapping pca.h defines, so a future mapping is a new name rather than a misreading.
constexpr const char* kTransform = "log-cosine-median";

const char* position_name(BinPosition p) { return p == BinPosition::Centre ? "centre" : "start"; }

// Whether a material is written with a reference to its basis file: when it was built or read so,
// and that file still holds its basis. A basis whose file has gone (deleted, or replaced by another
// basis) is embedded instead, so that what is written reads back.
bool stays_referenced(const PcaBrdf& p) {
    if (p.basis_storage() == PcaBrdf::BasisStorage::Embedded) return false;
    const PcaBasis::Origin& origin = p.basis().origin();
    if (origin.path.empty()) return true;  // write() refuses it, saying why
    try {
        return read_pca_basis(origin.path)->origin().sha256 == origin.sha256;
    } catch (const Error&) {
        return false;
    }
}

std::vector<Feature> needs(const Brdf& brdf) {
    const auto* p = dynamic_cast<const PcaBrdf*>(&brdf);
    if (!p) return {};
    std::vector<Feature> out{kPca};
    if (stays_referenced(*p)) out.push_back(kPcaExternal);
    if (p->basis().grid().full_circle()) out.push_back(kFullPhiD);
    return out;
}

std::vector<std::uint64_t> grid_shape(const GridSpec& g) {
    return {static_cast<std::uint64_t>(g.n_theta_h), static_cast<std::uint64_t>(g.n_theta_d),
            static_cast<std::uint64_t>(g.n_phi_d)};
}

void write(h5::WriteNode& rep, const Brdf& brdf) {
    const auto& p = dynamic_cast<const PcaBrdf&>(brdf);
    const PcaBasis& basis = p.basis();
    const bool embedded = !stays_referenced(p);
    if (!embedded && basis.origin().path.empty())
        throw ValueError(rep.file() + ": the PCA basis was not read from a file, so it cannot be referenced; "
                                      "save it first (write_pca_basis) or embed it");
    const std::vector<std::uint64_t> g = grid_shape(basis.grid());
    rep.attr("grid", std::span<const std::uint64_t>(g));
    rep.attr("bin_position", std::string(position_name(basis.grid().position)));
    rep.attr("theta_h_axis", std::string("sqrt"));
    write_phi_d_axis(rep, basis.grid());
    rep.attr("transform", std::string(kTransform));
    rep.attr("epsilon", basis.epsilon());
    rep.attr("k", std::uint64_t(p.k()));
    rep.attr("k_max", std::uint64_t(basis.k_max()));
    rep.attr("basis_storage", std::string(embedded ? "embedded" : "referenced"));
    // A basis read from a file carries the hash checked when it was read; a new one is hashed here.
    rep.attr("basis_sha256", basis.origin().sha256.empty() ? pca_basis_sha256(basis) : basis.origin().sha256);
    if (p.k() > 0) rep.dataset("coefficients", h5::DType::F32, {std::uint64_t(p.k())}, p.coefficients().data());
    write_sampler(rep, p.table().sampler());
    if (!embedded) {
        const std::filesystem::path dir = std::filesystem::absolute(rep.file()).parent_path();
        rep.attr("basis_file", std::filesystem::absolute(basis.origin().path).lexically_relative(dir).generic_string());
        return;
    }
    const std::vector<std::uint64_t> table{g[0], g[1], g[2], 3};
    rep.dataset("median", h5::DType::F32, table, basis.median().data());
    rep.dataset("mean", h5::DType::F32, table, basis.mean().data());
    rep.dataset("components", h5::DType::F32, {std::uint64_t(basis.k_max()), g[0], g[1], g[2], 3},
                basis.components().data());
    rep.dataset("variances", h5::DType::F64, {std::uint64_t(basis.k_max())}, basis.variances().data());
}

// Little-endian bytes of an array into the hash.
template <typename T>
void hash_array(Sha256& h, std::span<const T> values) {
    if constexpr (std::endian::native == std::endian::little) {
        h.update(values.data(), values.size_bytes());
    } else {
        for (T v : values) {
            const T le = brdfz::detail::to_little_endian(v);
            h.update(&le, sizeof le);
        }
    }
}

// pca_basis_sha256 of a basis's parts, before a basis is built from them.
std::string basis_sha256(const GridSpec& g, double epsilon, std::span<const float> median, std::span<const float> mean,
                         std::span<const float> components, std::span<const double> variances) {
    char record[256];
    // A basis over the full φd circle says so in its grid line (a reciprocal one's record is unchanged).
    std::snprintf(record, sizeof record, "brdfz pca basis 1\ngrid %dx%dx%d %s%s\ntransform %s %.17g\nk_max %zu\n",
                  g.n_theta_h, g.n_theta_d, g.n_phi_d, position_name(g.position), g.reciprocal() ? "" : " phi_d full",
                  kTransform, epsilon, variances.size());
    Sha256 h;
    h.update(record, std::strlen(record));
    hash_array(h, median);
    hash_array(h, mean);
    hash_array(h, components);
    hash_array(h, variances);
    return hex(h.finish());
}

// A dataset of `type` and exactly `shape`, read whole.
template <typename T>
std::vector<T> read_exact(const h5::ReadNode& rep, const std::string& name, h5::DType type,
                          const std::vector<std::uint64_t>& shape) {
    const h5::Dataset d = rep.dataset(name);
    if (d.type() != type || d.shape() != shape) {
        std::string dims;
        for (std::uint64_t s : shape) {
            if (!dims.empty()) dims += 'x';
            dims += std::to_string(s);
        }
        throw FormatError(rep.file(), d.path() + ": expected " + h5::dtype_name(type) + " [" + dims + "]");
    }
    std::vector<T> out(d.count());
    d.read(out.data());
    return out;
}

std::shared_ptr<const PcaBasis> read_embedded(const h5::ReadNode& rep, const GridSpec& grid, double epsilon,
                                              std::uint64_t k_max, const std::string& stored_hash) {
    const std::vector<std::uint64_t> g = grid_shape(grid);
    const std::vector<std::uint64_t> table{g[0], g[1], g[2], 3};
    // The components' declared shape is bounded by the file's size before anything is allocated.
    std::vector<float> median = read_exact<float>(rep, "median", h5::DType::F32, table);
    std::vector<float> mean = read_exact<float>(rep, "mean", h5::DType::F32, table);
    std::vector<float> components = read_exact<float>(rep, "components", h5::DType::F32, {k_max, g[0], g[1], g[2], 3});
    std::vector<double> variances = read_exact<double>(rep, "variances", h5::DType::F64, {k_max});
    const std::string hash = basis_sha256(grid, epsilon, median, mean, components, variances);
    if (hash != stored_hash)
        throw FormatError(rep.file(), rep.path() + ": the embedded basis has content hash " + hash +
                                          ", the file records " + stored_hash);
    try {
        return std::make_shared<const PcaBasis>(grid, epsilon, std::move(median), std::move(mean), std::move(components),
                                                std::move(variances), PcaBasis::Origin{rep.file(), hash});
    } catch (const ValueError& e) {
        throw FormatError(rep.file(), rep.path() + ": " + e.what());
    }
}

std::shared_ptr<const PcaBasis> read_referenced(const h5::ReadNode& rep, const GridSpec& grid,
                                                const std::string& stored_hash) {
    const std::string name = rep.str("basis_file");
    if (name.empty()) throw FormatError(rep.file(), rep.path() + ": attribute 'basis_file' is empty");
    const std::filesystem::path path = std::filesystem::absolute(rep.file()).parent_path() / name;
    if (!std::filesystem::exists(path))
        throw IoError(path.string(), "PCA basis file not found (referenced by " + rep.file() + " as '" + name + "')");
    std::shared_ptr<const PcaBasis> basis = read_pca_basis(path.string());
    if (basis->origin().sha256 != stored_hash)
        throw FormatError(rep.file(), "PCA basis file '" + name + "' has content hash " + basis->origin().sha256 +
                                          ", but the material was made with basis " + stored_hash +
                                          " (a different or retrained basis)");
    if (!(basis->grid() == grid))
        throw FormatError(rep.file(), "PCA basis file '" + name + "' is on grid " + basis->grid().str() +
                                          ", the material records " + grid.str());
    return basis;
}

std::unique_ptr<Brdf> read(const h5::ReadNode& rep, const ReadContext& ctx) {
    const auto bad = [&](const std::string& what) { throw FormatError(rep.file(), rep.path() + ": " + what); };
    const std::string transform = rep.str("transform");
    if (transform != kTransform) bad("unknown transform '" + transform + "'");
    const GridSpec grid = read_grid(rep, false);
    const double epsilon = rep.f64("epsilon");
    const std::uint64_t k = rep.u64("k"), k_max = rep.u64("k_max");
    if (k_max < 1 || k > k_max) bad("k = " + std::to_string(k) + " and k_max = " + std::to_string(k_max) + " are inconsistent");
    const std::string storage = rep.str("basis_storage");
    if (storage != "embedded" && storage != "referenced") bad("unknown basis_storage '" + storage + "'");
    const std::string hash = rep.str("basis_sha256");
    if (hash.size() != 64) bad("attribute 'basis_sha256' is not 64 hex digits");

    std::vector<float> coefficients;
    if (k > 0) coefficients = read_exact<float>(rep, "coefficients", h5::DType::F32, {k});
    const bool embedded = storage == "embedded";
    std::shared_ptr<const PcaBasis> basis =
        embedded ? read_embedded(rep, grid, epsilon, k_max, hash) : read_referenced(rep, grid, hash);
    if (static_cast<std::uint64_t>(basis->k_max()) != k_max)
        bad("the basis has " + std::to_string(basis->k_max()) + " components, the file records " + std::to_string(k_max));
    std::unique_ptr<PcaBrdf> brdf;
    try {
        const PcaBrdf::BasisStorage stored = embedded ? PcaBrdf::BasisStorage::Embedded : PcaBrdf::BasisStorage::Referenced;
        brdf = with_sampler(rep, [&](auto sampler) {
            return std::make_unique<PcaBrdf>(std::move(basis), std::move(coefficients), ctx.lookup, stored,
                                             std::move(sampler));
        });
    } catch (const ValueError& e) {
        bad(e.what());
    }
    // Stored coefficients far outside the basis's range overflow where they are reconstructed.
    if (brdf->counts().inf > 0)
        bad("the coefficients reconstruct " + std::to_string(brdf->counts().inf) +
            " bins beyond the float range (a coefficient vector far outside the basis's training set)");
    return brdf;
}

// The range and validity of the reconstruction, which the object holds.
void source_info(const Brdf& brdf, SourceInfo& info) {
    const PcaBrdf& p = dynamic_cast<const PcaBrdf&>(brdf);
    ValidityCounts counts = info.counts;
    counts.valid = p.counts().valid;
    info = brdfz::detail::table_info(info.format, p.table().table(), counts);
    info.dims_of = "grid of the basis (" + std::to_string(p.k()) + " coefficients)";
}

}  // namespace

void register_pca(std::vector<const StorageModule*>& out) {
    static const StorageModule m{"pca", {kPca, kPcaExternal, kFullPhiD}, &needs, &write, &read, &source_info};
    out.push_back(&m);
}

}  // namespace detail

std::string pca_basis_sha256(const PcaBasis& basis) {
    return detail::basis_sha256(basis.grid(), basis.epsilon(), basis.median(), basis.mean(), basis.components(),
                                basis.variances());
}

std::shared_ptr<const PcaBasis> write_pca_basis(const std::string& path, PcaBasis basis) {
    // Hashed once: the storage module takes the hash from the origin.
    basis.set_origin({path, pca_basis_sha256(basis)});
    auto shared = std::make_shared<const PcaBasis>(std::move(basis));
    write(path, PcaBrdf(shared, {}, Lookup::Linear, PcaBrdf::BasisStorage::Embedded));
    return shared;
}

namespace {

// Bases already read, by file: many materials share one, and a basis is large. An entry is used only
// while the path names the same file (device and inode: writers replace files by renaming a new one
// onto them) with the size and modification time it had when it was read and verified.
struct FileId {
    dev_t dev;
    ino_t ino;
    off_t size;
    std::int64_t mtime_ns;
    bool operator==(const FileId&) const = default;
};
std::optional<FileId> file_id(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) return std::nullopt;
    return FileId{st.st_dev, st.st_ino, st.st_size, std::int64_t{st.st_mtim.tv_sec} * 1000000000 + st.st_mtim.tv_nsec};
}
struct CachedBasis {
    FileId id;
    std::weak_ptr<const PcaBasis> basis;
};
std::mutex cache_mutex;
std::map<std::string, CachedBasis> cache;

}  // namespace

std::shared_ptr<const PcaBasis> read_pca_basis(const std::string& path) {
    std::error_code ec;
    const std::string key = std::filesystem::weakly_canonical(path, ec).string();
    const std::optional<FileId> id = file_id(path);
    if (id && !ec) {
        std::lock_guard lock(cache_mutex);
        const auto it = cache.find(key);
        if (it != cache.end() && it->second.id == *id)
            if (auto basis = it->second.basis.lock()) return basis;
    }
    ReadResult r = read(path);
    const auto* p = dynamic_cast<const PcaBrdf*>(r.brdf.get());
    if (!p) throw FormatError(path, "not a PCA basis file (it holds a '" + r.meta.representation + "' representation)");
    if (p->basis_storage() != PcaBrdf::BasisStorage::Embedded)
        throw FormatError(path, "not a PCA basis file (a PCA material that refers to its basis in another file)");
    if (id && !ec) {
        std::lock_guard lock(cache_mutex);
        cache[key] = {*id, p->shared_basis()};
    }
    return p->shared_basis();
}

}  // namespace brdfz::container
