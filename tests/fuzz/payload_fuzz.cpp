// libFuzzer harness: hostile values inside valid envelopes. The byte flips of the other harnesses
// rarely get past the container's checksums, so here the input is the payload itself: its first byte
// picks what it fills (a float32 table, SVD factors, analytic parameters, RGL tensors in a container
// or in a .bsdf, a PCA material with its basis embedded), the rest are that payload's float32 (or
// float64) values, written with correct checksums, hashes and shapes (tests/robustness/envelope.h). A file must then be refused, or load and give
// finite results: eval >= 0 (RGL data may hold negative reflectance, which Mitsuba renders too), pdf
// finite and >= 0, sampled weights finite. Anything else aborts.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/io.h"
#include "brdfz/repr/analytic/model.h"
#include "brdfz/repr/pca.h"
#include "brdfz/tabulate.h"
#include "fuzz_util.h"
#include "robustness/envelope.h"

namespace {

using namespace brdfz;

// `n` values of T from the input after `pos`, the input repeated as needed (a short input still
// fills every slot); plausible values where the input is empty.
template <typename T>
std::vector<T> values(const std::uint8_t* data, std::size_t size, std::size_t n, T fallback) {
    std::vector<T> out(n, fallback);
    const std::size_t count = size / sizeof(T);
    for (std::size_t k = 0; count && k < n; ++k) std::memcpy(&out[k], data + sizeof(T) * (k % count), sizeof(T));
    return out;
}

rgl::Tensors tensors(const std::uint8_t* data, std::size_t size) {
    const std::vector<float> v = values<float>(data, size, 3 + 16 + 16 + 48 + 144 + 48, 0.5f);
    rgl::Tensors t;
    std::size_t at = 3;  // the first three slots are theta_i's, kept fixed (their order is checked anyway)
    const auto take = [&](std::size_t n) {
        std::vector<float> part(v.begin() + static_cast<std::ptrdiff_t>(at), v.begin() + static_cast<std::ptrdiff_t>(at + n));
        at += n;
        return part;
    };
    t.theta_i = {0.0f, 0.7f, 1.4f};
    const auto grids = [&](std::size_t slices) {
        rgl::Grids g;
        g.slices = slices;
        g.rows = g.cols = 4;
        g.values = take(slices * 16);
        return g;
    };
    t.ndf = grids(1);
    t.sigma = grids(1);
    t.vndf = grids(3);
    t.rgb = grids(9);
    t.luminance = grids(3);
    return t;
}

// A PCA material whose basis parts and coefficients are the input's values, laid over a basis trained
// on three analytic tables: the bins that basis drops (below the horizon) stay dropped, since a basis
// that keeps them is refused whatever its values.
test::PcaParts pca_parts(const std::uint8_t* data, std::size_t size) {
    static const test::PcaParts trained = [] {
        const GridSpec g{2, 3, 4};
        std::vector<Table> tables;
        for (double alpha : {0.1, 0.3}) {
            TabulateOptions o;
            o.grid = g;
            tables.push_back(tabulate(AnalyticBrdf("lambert+ggx", {0.3, 0.4, 0.5, 0.5, 0.5, 0.5, alpha, 0.04}), o).table);
        }
        const std::vector<const Table*> ptrs{&tables[0], &tables[1]};
        PcaTrainOptions o;
        o.k_max = 2;
        const PcaBasis b = train_pca_basis(ptrs, o);
        return test::PcaParts{2, 3, 4, b.epsilon(), {b.median().begin(), b.median().end()},
                              {b.mean().begin(), b.mean().end()}, {b.components().begin(), b.components().end()},
                              std::vector<float>(2, 0.0f), {b.variances().begin(), b.variances().end()}};
    }();
    test::PcaParts p = trained;
    const std::vector<float> v = values<float>(data, size, 72 + 72 + 144 + 2 + 2, 0.5f);
    auto at = v.begin();
    for (float& m : p.median) {
        if (!std::isnan(m)) m = *at;
        ++at;
    }
    for (std::vector<float>* part : {&p.mean, &p.components, &p.coefficients})
        for (float& x : *part) x = *at++;
    for (double& x : p.variances) x = *at++;
    return p;
}

void check(const Brdf& b, bool non_negative) {
    const Vec3 dirs[] = {{0, 0, 1}, {0.6, 0, 0.8}, {-0.3, 0.4, 0.866}, {0.99, 0.1, 0.0999}, {0, -0.999, 0.0447}};
    for (const Vec3& a : dirs)
        for (const Vec3& c : dirs) {
            const Vec3 wi = normalize(a), wo = normalize(c);
            for (double f : b.eval(wi, wo))
                if (!std::isfinite(f) || (non_negative && f < 0.0)) std::abort();
            const double p = b.pdf(wo, wi);
            if (!(std::isfinite(p) && p >= 0.0)) std::abort();
            const BrdfSample s = b.sample(wo, 0.3, 0.7);
            if (!(std::isfinite(s.pdf) && s.pdf >= 0.0)) std::abort();
            for (double w : s.weight)
                if (!std::isfinite(w)) std::abort();
        }
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    if (size == 0) return 0;
    const int kind = data[0] % 6;
    ++data, --size;
    static const std::string base = fuzz::input_file(nullptr, 0, ".payload");
    const std::string path = base + (kind == 4 ? ".bsdf" : ".brdfz");
    try {
        switch (kind) {
            case 0: test::write_float32_table(path, 2, 3, 4, values<float>(data, size, 72, 0.5f)); break;
            case 1: {
                const std::vector<float> v = values<float>(data, size, 6 + 36, 0.5f);
                test::write_factors(path, 2, 3, 4, {v.begin(), v.begin() + 6}, {v.begin() + 6, v.end()});
                break;
            }
            case 2: {
                const Model m = Model::parse("lambert+ggx");
                std::vector<std::string> names;
                for (std::size_t k = 0; k < m.size(); ++k) names.push_back(m.name(k));
                test::write_analytic(path, "lambert+ggx", names, values<double>(data, size, m.size(), 0.5));
                break;
            }
            case 3: test::write_rgl_container(path, tensors(data, size)); break;
            case 4: test::write_bsdf(path, tensors(data, size)); break;
            default: test::write_pca(path, pca_parts(data, size)); break;
        }
    } catch (const Error&) {
        std::abort();  // the envelope itself must always be writable
    }
    try {
        const Loaded l = load(path);
        check(*l.brdf, kind < 3 || kind == 5);
    } catch (const Error&) {
    }
    return 0;
}
