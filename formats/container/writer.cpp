#include <charconv>
#include <cstdint>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <string_view>

#include "brdfz/errors.h"
#include "brdfz/repr/compact_table.h"
#include "brdfz/tabulate.h"
#include "checksum.h"
#include "storage.h"

#ifndef BRDFZ_VERSION
#error "BRDFZ_VERSION must be defined by the build (the project version)"
#endif

namespace brdfz::container {
namespace {

// The `created` time: now, or SOURCE_DATE_EPOCH (reproducible-builds.org) when it is set, so that two
// runs write identical bytes.
std::string created_time() {
    std::time_t now = std::time(nullptr);
    if (const char* epoch = std::getenv("SOURCE_DATE_EPOCH")) {
        const std::string_view text(epoch);
        std::int64_t seconds = -1;
        const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), seconds);
        if (text.empty() || ec != std::errc() || end != text.data() + text.size() || seconds < 0)
            throw ValueError("SOURCE_DATE_EPOCH='" + std::string(text) + "' is not a number of seconds since 1970");
        now = static_cast<std::time_t>(seconds);
    }
    std::tm tm{};
    gmtime_r(&now, &tm);
    char buf[32];
    std::strftime(buf, sizeof buf, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return buf;
}

void write_metrics(h5::WriteNode& node, const char* name, const PerChannel& v) {
    const double values[4] = {v.r, v.g, v.b, v.mean};
    node.attr(name, std::span<const double>(values));
}

void write_achieved(h5::WriteNode& node, const Achieved& a) {
    node.attr("lossless", std::uint64_t{a.lossless});
    node.attr("nbytes", a.nbytes);
    const ValidityCounts& c = a.counts;
    const std::uint64_t counts[6] = {c.valid, c.negative, c.nan, c.inf, c.clamped, c.below_horizon};
    node.attr("counts", std::span<const std::uint64_t>(counts));
    if (!a.metrics) return;
    const Metrics& m = *a.metrics;
    write_metrics(node, "cos_rmse", m.cos_rmse);
    write_metrics(node, "cos_rmse_rel", m.cos_rmse_rel);
    write_metrics(node, "log_rmse", m.log_rmse);
    write_metrics(node, "cbrt_rmse", m.cbrt_rmse);
    node.attr("metric_samples", std::uint64_t{m.samples});
    node.attr("metric_negatives", std::uint64_t{m.negatives});
}

}  // namespace

Achieved write(const std::string& path, const Brdf& brdf, const WriteOptions& options) {
    using detail::StorageModule;
    // Stored as it is when a module knows the object and no resampling is asked for; a table asked
    // for on its own grid is also stored as it is.
    const auto* table = dynamic_cast<const TabularBrdf*>(&brdf);
    const auto* compact = dynamic_cast<const CompactTableBrdf*>(&brdf);
    const StorageModule* module = nullptr;
    if (!options.grid || (table && *options.grid == table->table().grid()) ||
        (compact && *options.grid == compact->table().grid()))
        for (const StorageModule* m : detail::storage_modules())
            if (!m->needs(brdf).empty()) {
                module = m;
                break;
            }

    Achieved achieved;
    std::unique_ptr<Brdf> tabulated;
    const Brdf* stored = &brdf;
    if (module) {
        achieved.lossless = true;
        if (table) achieved.counts.valid = table->table().valid_bins();
        if (compact) achieved.counts.valid = compact->table().valid_bins();
        if (!table && !compact) {  // what the module stores: parameters, factors' bins, RGL values
            SourceInfo info;
            module->source_info(brdf, info);
            achieved.counts = info.counts;
        }
    } else {
        TabulateOptions t;
        t.grid = options.grid.value_or(GridSpec{});
        t.threads = options.threads;
        t.progress = options.progress;
        Tabulated tab = tabulate(brdf, t);
        achieved.counts = tab.counts;
        tabulated = std::make_unique<TabularBrdf>(std::move(tab.table), table ? table->lookup() : Lookup::Linear);
        stored = tabulated.get();
        module = detail::find_storage("tabular");
        if (options.metrics) {
            MetricOptions m;
            m.threads = options.threads;
            achieved.metrics = compare(brdf, *stored, m);
        }
    }
    achieved.nbytes = stored->nbytes();
    if (options.source_metrics) achieved.metrics = options.source_metrics;

    std::vector<Feature> features{detail::kCore};
    for (const Feature& f : module->needs(*stored)) features.push_back(f);
    std::vector<std::string> names;
    std::vector<std::uint64_t> since;
    std::uint32_t min_reader = 1;
    for (const Feature& f : features) {
        names.push_back(f.name);
        since.push_back(f.since);
        min_reader = std::max(min_reader, f.since);
    }

    Source source;
    if (!options.source.empty()) {
        source.file = std::filesystem::path(options.source).filename().string();
        source.format = options.source_format;
        source.sha256 = sha256_file(options.source);
    }

    {
        h5::Writer w(path);
        {
            h5::WriteNode root = w.root();
            root.attr("format", std::string("brdfz"));
            root.attr("version", std::uint64_t{kVersion});
            root.attr("min_reader_version", std::uint64_t{min_reader});
            root.attr("features", std::span<const std::string>(names));
            root.attr("feature_versions", std::span<const std::uint64_t>(since));
            root.attr("library_version", std::string(BRDFZ_VERSION));
            root.attr("created", created_time());
            root.attr("source_file", source.file);
            root.attr("source_format", source.format);
            root.attr("source_sha256", source.sha256);
            root.attr("units", std::string(detail::kUnits));
            root.attr("cosine", std::string(detail::kCosine));
            root.attr("conventions", std::string(detail::kConventions));
            h5::WriteNode rep = root.group("representation");
            rep.attr("type", std::string(module->type));
            rep.attr("spec", stored->describe());
            if (!options.build_spec.empty()) rep.attr("build_spec", options.build_spec);
            module->write(rep, *stored);
            h5::WriteNode ach = root.group("achieved");
            write_achieved(ach, achieved);
        }
        w.close();
    }
    return achieved;
}

}  // namespace brdfz::container
