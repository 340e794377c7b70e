#include "table_io.h"

#include <algorithm>
#include <cmath>
#include <limits>

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

// MERL and EXR files know only the linear θd axis, so a warped table is tabulated too.
ValidityCounts save_table(const Brdf& brdf, const SaveOptions& options, const std::function<void(const Table&)>& write) {
    const Table* table = brdf.stored_table();
    if (table && table->grid().theta_d_warp == 0.0 && (!options.grid || *options.grid == table->grid())) {
        write(*table);
        ValidityCounts written;
        written.valid = table->valid_bins();
        return written;
    }
    TabulateOptions t;
    t.grid = options.grid.value_or(GridSpec{});
    if (table && !options.grid) {  // a warped table: its own grid on the linear θd axis
        t.grid = table->grid();
        t.grid.theta_d_warp = 0.0;
    }
    t.threads = options.threads;
    t.progress = options.progress;
    Tabulated tab = tabulate(brdf, t);
    write(tab.table);
    return tab.counts;
}

}  // namespace brdfz::detail
