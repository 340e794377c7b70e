#include "table_io.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include "brdfz/errors.h"
#include "brdfz/tabulate.h"

namespace brdfz::detail {

SourceInfo table_info(const std::string& format, const Table& t, const ValidityCounts& counts) {
    SourceInfo info;
    info.format = format;
    const GridSpec& g = t.grid();
    info.dims = {static_cast<std::size_t>(g.n_theta_h), static_cast<std::size_t>(g.n_theta_d),
                 static_cast<std::size_t>(g.n_phi_d)};
    info.counts = counts;
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (std::size_t k = 0; k < 3 * t.bins(); ++k) {
        const float v = t.data()[k];
        if (std::isnan(v)) continue;
        lo = std::min<double>(lo, v);
        hi = std::max<double>(hi, v);
    }
    info.min_value = lo <= hi ? lo : 0.0;
    info.max_value = lo <= hi ? hi : 0.0;
    return info;
}

ValidityCounts invalidate_out_of_range(const std::string& path, Table& table) {
    ValidityCounts counts;
    std::size_t values = 0;  // valid channels: a bin with one of them still has something to evaluate
    float* v = table.data();
    for (std::size_t b = 0; b < table.bins(); ++b) {
        bool neg = false, nan = false, inf = false;
        for (int c = 0; c < 3; ++c) {
            float& x = v[3 * b + c];
            nan = nan || std::isnan(x);
            inf = inf || std::isinf(x);
            neg = neg || (x < 0.0f && !std::isinf(x));
            if (std::isinf(x) || x < 0.0f) x = std::numeric_limits<float>::quiet_NaN();
            values += !std::isnan(x);
        }
        counts.valid += !neg && !nan && !inf;
        counts.negative += neg;
        counts.nan += nan;
        counts.inf += inf;
    }
    if (values == 0) throw FormatError(path, "no valid value in the table (every entry is negative, NaN or Inf)");
    return counts;
}

// Table formats (MERL, EXR, NPY) know only the square-root θh axis, the linear θd axis and the reciprocal φd axis, so a warped
// table is tabulated too, a table over the full φd circle onto half as many φd bins over [0, π), and a
// bilateral table onto as many (each the mean of the pair and its exchange, tabulate.h).
ValidityCounts save_table(const Brdf& brdf, const SaveOptions& options, const std::function<void(const Table&)>& write) {
    if (options.grid && !options.grid->reciprocal())
        throw ValueError("MERL, EXR and NPY tables fold phi_d by reciprocity: a grid with symmetry " +
                         std::string(symmetry_name(options.grid->symmetry)) + " needs .brdfz");
    const Table* table = brdf.stored_table();
    const auto plain = [](const GridSpec& g) { return g.theta_d_warp == 0.0 && g.theta_h_warp == 0.0 && g.reciprocal(); };
    if (table && plain(table->grid()) && (!options.grid || *options.grid == table->grid())) {
        write(*table);
        ValidityCounts written;
        written.valid = table->valid_bins();
        return written;
    }
    TabulateOptions t;
    t.grid = options.grid.value_or(GridSpec{});
    if (table && !options.grid) {  // its own grid on the linear θd axis and the reciprocal φd axis
        t.grid = table->grid();
        t.grid.theta_d_warp = t.grid.theta_h_warp = 0.0;
        if (t.grid.full_circle()) t.grid.n_phi_d = std::max(1, t.grid.n_phi_d / 2);
        t.grid.symmetry = Symmetry::Reciprocal;
    }
    t.threads = options.threads;
    t.progress = options.progress;
    Tabulated tab = tabulate(brdf, t);
    write(tab.table);
    return tab.counts;
}

}  // namespace brdfz::detail
