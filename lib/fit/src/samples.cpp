#include "brdfz/fit/samples.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "brdfz/coords.h"
#include "brdfz/errors.h"
#include "brdfz/table.h"
#include "detail/parallel.h"
#include "detail/random.h"

namespace brdfz {

GridSamples sample_brdf(const Brdf& brdf, const SampleOptions& options) {
    if (!(options.max_theta_deg > 0.0 && options.max_theta_deg <= 90.0))
        throw ValueError("sample_brdf: max_theta_deg must be in (0, 90]");
    const Table* table = brdf.stored_table();
    const GridSpec g = table ? table->grid() : options.grid;
    g.validate();
    const double min_cos = std::fmax(std::cos(options.max_theta_deg * std::numbers::pi / 180.0), 0.0);

    // With φh = 0, wi.z = cosθd cosθh − sinθd cosφd sinθh and wo.z = cosθd cosθh + sinθd cosφd sinθh
    // (coords.h): eligibility needs no trigonometry per bin, so the whole grid is scanned cheaply.
    std::vector<double> ch(g.n_theta_h), sh(g.n_theta_h), cd(g.n_theta_d), sd(g.n_theta_d), cp(g.n_phi_d);
    for (int i = 0; i < g.n_theta_h; ++i) ch[i] = std::cos(g.theta_h_at(i)), sh[i] = std::sin(g.theta_h_at(i));
    for (int i = 0; i < g.n_theta_d; ++i) cd[i] = std::cos(g.theta_d_at(i)), sd[i] = std::sin(g.theta_d_at(i));
    for (int i = 0; i < g.n_phi_d; ++i) cp[i] = std::cos(g.phi_d_at(i));
    auto for_each_eligible = [&](auto&& visit) {
        for (int ih = 0; ih < g.n_theta_h; ++ih)
            for (int id = 0; id < g.n_theta_d; ++id) {
                const double a = cd[id] * ch[ih], b = sd[id] * sh[ih];
                for (int ip = 0; ip < g.n_phi_d; ++ip)
                    if (a - b * cp[ip] > min_cos && a + b * cp[ip] > min_cos) visit(ih, id, ip);
            }
    };

    GridSamples out;
    for_each_eligible([&](int, int, int) { ++out.eligible; });
    const double keep = options.max_samples == 0 || options.max_samples >= out.eligible
                            ? 1.0
                            : static_cast<double>(options.max_samples) / static_cast<double>(out.eligible);

    std::vector<Vec3> wi, wo;
    std::vector<std::size_t> bins;
    for_each_eligible([&](int ih, int id, int ip) {
        const std::size_t bin = g.index(ih, id, ip);
        if (keep < 1.0 && detail::unit_hash(bin, options.seed) >= keep) return;
        const auto [i, o] = from_half_diff({g.theta_h_at(ih), 0.0, g.theta_d_at(id), g.phi_d_at(ip)});
        wi.push_back(i);
        wo.push_back(o);
        bins.push_back(bin);
    });

    std::vector<Rgb> f(wi.size());
    if (table) {
        for (std::size_t k = 0; k < bins.size(); ++k)
            for (int c = 0; c < 3; ++c) f[k][c] = table->at(bins[k], c);  // NaN marks invalid
    } else {
        // Sources can be slow to evaluate (RGL): split the batch over threads.
        const std::size_t workers = std::min<std::size_t>(resolve_threads(options.threads), wi.size() / 1024 + 1);
        const std::size_t per = (wi.size() + workers - 1) / workers;
        detail::parallel_for(static_cast<int>(workers), static_cast<int>(workers), [&](int, int w) {
            const std::size_t begin = std::min(wi.size(), w * per), n = std::min(wi.size(), begin + per) - begin;
            brdf.eval(std::span(wi).subspan(begin, n), std::span(wo).subspan(begin, n), std::span(f).subspan(begin, n));
        });
    }

    out.set.channels = brdf.channels();
    out.set.source = brdf.describe();
    out.set.samples.reserve(wi.size());
    for (std::size_t k = 0; k < wi.size(); ++k) {
        if (!(std::isfinite(f[k][0]) && std::isfinite(f[k][1]) && std::isfinite(f[k][2]))) {
            ++out.invalid;
            continue;
        }
        out.set.samples.push_back({wi[k], wo[k], f[k]});
    }
    return out;
}

}  // namespace brdfz
