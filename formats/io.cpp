#include "brdfz/formats/io.h"

#include <algorithm>
#include <filesystem>
#include <fstream>

#include "brdfz/errors.h"
#include "detail/atomic_file.h"
#include "brdfz/formats/pca_basis.h"
#include "brdfz/formats/registry.h"

namespace brdfz {
namespace formats {
// Generated from the folders formats/*/ that hold a format.cpp (cmake/registry.cmake).
void register_all(std::vector<Format>& out);
}  // namespace formats

namespace {

bool readable(const Format& f) { return f.read || f.read_measurements; }

// "x (.a, .b)" for every format `accepts`.
template <typename Accepts>
std::string extension_list(Accepts accepts) {
    std::string out;
    for (const Format& f : all_formats()) {
        if (!accepts(f)) continue;
        for (const std::string& ext : f.extensions) out += (out.empty() ? "" : ", ") + ext;
    }
    return out;
}

const Format* by_extension(const std::string& path) {
    const std::string ext = std::filesystem::path(path).extension().string();
    for (const Format& f : all_formats())
        if (std::find(f.extensions.begin(), f.extensions.end(), ext) != f.extensions.end()) return &f;
    return nullptr;
}

const Format& named(const std::string& name, const std::string& path) {
    const Format* f = find_format(name);
    if (!f) {
        std::string known;
        for (const Format& g : all_formats()) known += (known.empty() ? "" : ", ") + g.name;
        throw UnsupportedError(path, "unknown format '" + name + "' (known: " + known + ")");
    }
    return *f;
}

const Format& detected(const std::string& path) { return named(detect_format(path), path); }

// Readers take regular files by name: a pipe (standard input) or a device cannot be sized and checked
// before it is read, and opening a FIFO blocks until something writes to it.
void check_regular(const std::string& path) {
    std::error_code ec;
    const std::filesystem::file_status st = std::filesystem::status(path, ec);
    const bool missing = ec || st.type() == std::filesystem::file_type::not_found;
    if ((missing && path == "-") ||
        (!missing && st.type() != std::filesystem::file_type::regular && st.type() != std::filesystem::file_type::directory))
        throw UnsupportedError(path, "standard input, pipes and devices are not read: give a file's name");
}

}  // namespace

const std::vector<Format>& all_formats() {
    static const std::vector<Format> all = [] {
        std::vector<Format> out;
        formats::register_all(out);
        std::sort(out.begin(), out.end(), [](const Format& a, const Format& b) { return a.name < b.name; });
        return out;
    }();
    return all;
}

const Format* find_format(std::string_view name) {
    for (const Format& f : all_formats())
        if (f.name == name) return &f;
    return nullptr;
}

std::string format_of(const std::string& path, Access access) {
    const Format* f = by_extension(path);
    const bool write = access == Access::Write;
    if (f && (write ? f->write != nullptr : readable(*f))) return f->name;
    const std::string ext = std::filesystem::path(path).extension().string();
    const std::string expected = write ? extension_list([](const Format& g) { return g.write != nullptr; })
                                       : extension_list(readable);
    if (f) throw UnsupportedError(path, std::string(write ? "writing " : "reading ") + f->name + " files is not supported (" +
                                            (write ? "writable" : "readable") + ": " + expected + ")");
    throw FormatError(path, "unknown file extension '" + ext + "' (expected " + expected + ")");
}

std::string detect_format(const std::string& path) {
    check_regular(path);
    if (const Format* f = by_extension(path); f && readable(*f)) return f->name;
    const std::string ext = std::filesystem::path(path).extension().string();
    const std::string expected = extension_list(readable);
    std::error_code ec;
    const std::uintmax_t size = std::filesystem::file_size(path, ec);
    if (ec) throw FormatError(path, "unknown file extension '" + ext + "' (expected " + expected + ")");
    std::ifstream in(path, std::ios::binary);
    if (!in) throw FormatError(path, "unknown file extension '" + ext + "' (expected " + expected + ")");
    std::string head(Format::kSniffBytes, '\0');
    in.read(head.data(), static_cast<std::streamsize>(head.size()));
    head.resize(static_cast<std::size_t>(in.gcount()));
    std::vector<std::string> matches;
    for (const Format& f : all_formats())
        if (readable(f) && f.sniff && f.sniff(head, size)) matches.push_back(f.name);
    if (matches.size() == 1) return matches.front();
    if (matches.empty())
        throw FormatError(path, "unknown file extension '" + ext + "' and contents of no known format (expected " +
                                    expected + ")");
    throw FormatError(path, "unknown file extension '" + ext + "', and the contents fit both " + matches[0] + " and " +
                                matches[1] + ": name the format");
}

Loaded load(const std::string& path, const LoadOptions& options) { return load_as(detect_format(path), path, options); }

Loaded load_as(const std::string& format, const std::string& path, const LoadOptions& options) {
    check_regular(path);
    const Format& f = named(format, path);
    if (f.read) return f.read(path, options);
    if (f.read_measurements)
        throw UnsupportedError(path, "a " + f.name + " file holds scattered measurements, not a BRDF: it can be the " +
                                         "reference of a comparison or be fitted, not evaluated");
    throw UnsupportedError(path, "reading " + f.name + " files is not supported");
}

bool holds_measurements(const std::string& path) { return detected(path).read_measurements != nullptr; }

LoadedMeasurements load_measurements(const std::string& path) {
    const Format& f = detected(path);
    if (!f.read_measurements)
        throw UnsupportedError(path, "a " + f.name + " file holds a BRDF, not scattered measurements: load it with load()");
    LoadedMeasurements out = f.read_measurements(path);
    out.info.format = f.name;
    // Readers keep only finite samples, and at least one.
    out.info.min_value = out.info.max_value = out.set.samples.front().f[0];
    for (const Measurement& m : out.set.samples)
        for (double v : m.f) {
            out.info.min_value = std::min(out.info.min_value, v);
            out.info.max_value = std::max(out.info.max_value, v);
        }
    return out;
}

ValidityCounts save(const Brdf& brdf, const std::string& path, const SaveOptions& options) {
    const Format& f = named(options.format.empty() ? format_of(path, Access::Write) : options.format, path);
    if (!f.write) throw UnsupportedError(path, "writing " + f.name + " files is not supported");
    check_output(path);
    return f.write(brdf, path, options);
}

ValidityCounts convert(const std::string& in, const std::string& out, const ConvertOptions& options) {
    check_output(out);
    const Loaded loaded = load_as(options.from.empty() ? detect_format(in) : options.from, in, options.load);
    SaveOptions save_options = options.save;
    save_options.source = in;
    save_options.source_format = loaded.info.format;
    return save(*loaded.brdf, out, save_options);
}

CompressOptions with_file_access(CompressOptions options) {
    options.load_pca_basis = [](const std::string& path) { return container::read_pca_basis(path); };
    return options;
}

void save_text(const std::string& path, std::string_view text) {
    detail::AtomicFile file(path);
    file.write(text.data(), text.size());
    file.commit();
}

}  // namespace brdfz
