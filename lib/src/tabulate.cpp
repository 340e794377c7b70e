#include "brdfz/tabulate.h"

#include <cmath>
#include <vector>

#include "detail/grid_sweep.h"

namespace brdfz {

Tabulated tabulate(const Brdf& brdf, const TabulateOptions& options) {
    const GridSpec& g = options.grid;
    Tabulated result{Table(g), {}};
    const int workers = detail::resolve_threads(options.threads);
    std::vector<ValidityCounts> counts(workers);
    std::vector<std::vector<Rgb>> scratch(workers);

    detail::sweep_slices(
        g, workers,
        [&](int worker, int ih, std::span<const Vec3> wi, std::span<const Vec3> wo) {
            std::vector<Rgb>& f = scratch[worker];
            f.resize(wi.size());
            brdf.eval(wi, wo, f);
            ValidityCounts& n = counts[worker];
            const std::size_t base = g.index(ih, 0, 0);
            for (std::size_t k = 0; k < wi.size(); ++k) {
                const std::size_t bin = base + k;
                if (!(wi[k].z > 0.0 && wo[k].z > 0.0)) {
                    ++n.below_horizon;  // left invalid
                    continue;
                }
                bool neg = false, nan = false, inf = false, clamped = false;
                Rgb v = f[k];
                for (double& c : v) {
                    if (std::isnan(c)) {
                        nan = true;
                    } else if (std::isinf(c) || std::isinf(static_cast<float>(c))) {
                        inf = true;
                    } else if (c < 0.0) {
                        if (options.negative == NegativePolicy::Clamp) {
                            c = 0.0;
                            clamped = true;
                        } else {
                            neg = true;
                        }
                    }
                }
                n.nan += nan;
                n.inf += inf;
                n.negative += neg;
                n.clamped += clamped;
                if (nan || inf || neg) continue;
                ++n.valid;
                result.table.set(bin, v);
            }
        },
        options.progress ? std::function<void(int, int)>([&](int done, int total) {
            options.progress(static_cast<double>(done) / total);
        })
                         : nullptr);

    for (const ValidityCounts& n : counts) {
        result.counts.valid += n.valid;
        result.counts.negative += n.negative;
        result.counts.nan += n.nan;
        result.counts.inf += n.inf;
        result.counts.clamped += n.clamped;
        result.counts.below_horizon += n.below_horizon;
    }
    return result;
}

}  // namespace brdfz
