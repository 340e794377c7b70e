#include "brdfz/repr/factored.h"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>

#include "brdfz/errors.h"
#include "repr/factored_impl.h"

namespace brdfz {
namespace {

// ---------------------------------------------------------------------------------------------
// Names

template <typename E>
struct Named {
    E value;
    const char* name;
};

constexpr Named<FactorMethod> kMethods[] = {{FactorMethod::Svd, "svd"}, {FactorMethod::Nmf, "nmf"}};
constexpr Named<FactorSpace> kSpaces[] = {
    {FactorSpace::Linear, "linear"}, {FactorSpace::Cos, "cos"}, {FactorSpace::Log, "log"}, {FactorSpace::Cbrt, "cbrt"}};
constexpr Named<FactorLayout> kLayouts[] = {{FactorLayout::HxDP, "h_dp"}, {FactorLayout::HDxP, "hd_p"}};
constexpr Named<FactorColour> kColours[] = {{FactorColour::Separate, "separate"}, {FactorColour::Shared, "shared"}};
constexpr Named<FactorFit> kFits[] = {{FactorFit::Samples, "samples"}, {FactorFit::LeastSquares, "lsq"}};
constexpr Named<FactorDtype> kDtypes[] = {{FactorDtype::F32, "f32"}, {FactorDtype::F16, "f16"}};

template <typename E, std::size_t N>
const char* name_of(const Named<E> (&table)[N], E value) {
    for (const Named<E>& n : table)
        if (n.value == value) return n.name;
    return "?";
}

template <typename E, std::size_t N>
E parse(const Named<E> (&table)[N], const std::string& name, const char* what) {
    std::string known;
    for (const Named<E>& n : table) {
        if (name == n.name) return n.value;
        known += (known.empty() ? "" : ", ") + std::string(n.name);
    }
    throw ValueError(std::string("unknown factorisation ") + what + " '" + name + "' (expected " + known + ")");
}

// Separate colour of rank 3 or 4 (the full-grid svd rank 4 and nmf rank 3 among them): the padded
// rows hold channel c's components from float 4c, so each channel is one group of 4 floats and the
// blend sums the product's groups directly, without the one-hot colour mix (3 loads and 3
// multiply-adds per step). The padded width stays what 3·rank rounds up to: 12 (SSE2) or 16 (AVX2).
bool grouped_channels(const Factors& f) { return f.colour == FactorColour::Separate && (f.rank == 3 || f.rank == 4); }

}  // namespace

// ---------------------------------------------------------------------------------------------

const char* factor_method_name(FactorMethod m) { return name_of(kMethods, m); }
const char* factor_space_name(FactorSpace s) { return name_of(kSpaces, s); }
const char* factor_layout_name(FactorLayout l) { return name_of(kLayouts, l); }
const char* factor_colour_name(FactorColour c) { return name_of(kColours, c); }
FactorMethod parse_factor_method(const std::string& name) { return parse(kMethods, name, "method"); }
FactorSpace parse_factor_space(const std::string& name) { return parse(kSpaces, name, "space"); }
FactorLayout parse_factor_layout(const std::string& name) { return parse(kLayouts, name, "layout"); }
FactorColour parse_factor_colour(const std::string& name) { return parse(kColours, name, "colour"); }
const char* factor_fit_name(FactorFit f) { return name_of(kFits, f); }
const char* factor_dtype_name(FactorDtype d) { return name_of(kDtypes, d); }
FactorFit parse_factor_fit(const std::string& name) { return parse(kFits, name, "fit"); }
FactorDtype parse_factor_dtype(const std::string& name) { return parse(kDtypes, name, "dtype"); }

int Factors::rows() const {
    return layout == FactorLayout::HxDP ? grid.n_theta_h : grid.n_theta_h * grid.n_theta_d;
}
int Factors::columns() const {
    return layout == FactorLayout::HxDP ? grid.n_theta_d * grid.n_phi_d : grid.n_phi_d;
}

FactoredBrdf::FactoredBrdf(Factors factors, CompactSampler sampler) : FactoredBrdf(std::move(factors), SamplerKind::None) {
    sampler_ = GridSampler(std::move(sampler));
}

FactoredBrdf::FactoredBrdf(Factors factors, SamplerKind sampler) : f_(std::move(factors)) {
    f_.grid.validate();
    const std::size_t rows = static_cast<std::size_t>(f_.rows()), cols = static_cast<std::size_t>(f_.columns());
    if (f_.rank < 1 || static_cast<std::size_t>(f_.rank) > std::min(rows, cols))
        throw ValueError("factored: rank " + std::to_string(f_.rank) + " outside 1.." +
                         std::to_string(std::min(rows, cols)) + " for grid " + f_.grid.str() + " in layout " +
                         factor_layout_name(f_.layout));
    const std::size_t m = static_cast<std::size_t>(f_.row_width());
    const std::size_t colours = f_.colour == FactorColour::Shared ? 3 * static_cast<std::size_t>(f_.rank) : 0;
    if (f_.u.size() != rows * m || f_.v.size() != cols * m || f_.colour_weights.size() != colours)
        throw ValueError("factored: factor sizes " + std::to_string(f_.u.size()) + ", " + std::to_string(f_.v.size()) +
                         ", " + std::to_string(f_.colour_weights.size()) + " do not match " +
                         std::to_string(rows * m) + ", " + std::to_string(cols * m) + ", " + std::to_string(colours));
    for (const std::vector<float>* values : {&f_.u, &f_.v, &f_.colour_weights})
        for (float x : *values)
            if (!std::isfinite(x)) throw ValueError("factored: a factor entry is not finite");
    {
        // Every reconstruction is a sum of products u·v (times a colour weight): bounded by the
        // components' largest magnitudes, which must keep it far inside the float range so that no
        // partial sum in the kernels overflows to Inf or NaN (a file's 3e38 entries would).
        std::vector<double> top_u(m, 0.0), top_v(m, 0.0);
        for (std::size_t i = 0; i < f_.u.size(); ++i) top_u[i % m] = std::max(top_u[i % m], std::fabs(double{f_.u[i]}));
        for (std::size_t i = 0; i < f_.v.size(); ++i) top_v[i % m] = std::max(top_v[i % m], std::fabs(double{f_.v[i]}));
        const std::size_t rank = static_cast<std::size_t>(f_.rank);
        for (std::size_t c = 0; c < 3; ++c) {
            double bound = 0.0;
            for (std::size_t j = 0; j < rank; ++j)
                bound += f_.colour == FactorColour::Shared
                             ? std::fabs(double{f_.colour_weights[c * rank + j]}) * top_u[j] * top_v[j]
                             : top_u[c * rank + j] * top_v[c * rank + j];
            if (!(bound <= 0.25 * std::numeric_limits<float>::max()))
                throw ValueError("factored: channel " + std::to_string(c) + "'s factors could reconstruct values up to " +
                                 std::to_string(bound) + " in magnitude, beyond the float range");
        }
    }
    if (f_.dtype == FactorDtype::F16)
        for (std::vector<float>* values : {&f_.u, &f_.v})
            for (float& x : *values) {
                const Eigen::half h(x);
                if (!std::isfinite(static_cast<float>(h)))
                    throw ValueError("factored: a factor entry (" + std::to_string(x) + ") is beyond the float16 range");
                x = static_cast<float>(h);
            }
    for (int c = 0; c < 3; ++c) {
        const float top = f_.max_value[c];
        if (!(top >= 0.0f)) throw ValueError("factored: max_value " + std::to_string(top) + " is not a value >= 0");
        ceiling_[c] = detail::to_space(f_.space, std::min(top, std::numeric_limits<float>::max()));
    }
    // The evaluation copies: rows padded to a whole number of the kernel's SIMD steps.
    simd_ = detail::simd_level();
    const std::size_t step = detail::factor_lanes(simd_);
    width_ = (m + step - 1) / step * step;
    // U and V each from a 64-byte boundary: a row of 16 floats (separate colour to rank 5, shared to
    // rank 16, under AVX) then fills one cache line instead of straddling two.
    constexpr std::size_t kLine = 64 / sizeof(float);
    const std::size_t v_offset = (rows * width_ + kLine - 1) / kLine * kLine;
    storage_.assign(v_offset + cols * width_ + kLine - 1, 0.0f);
    float* u = storage_.data() + (kLine - reinterpret_cast<std::uintptr_t>(storage_.data()) / sizeof(float) % kLine) % kLine;
    float* v = u + v_offset;
    const bool grouped = grouped_channels(f_);
    const std::size_t rank = static_cast<std::size_t>(f_.rank);
    const auto copy_row = [&](const float* from, float* to) {
        if (grouped)
            for (std::size_t c = 0; c < 3; ++c) std::copy_n(from + c * rank, rank, to + 4 * c);
        else
            std::copy_n(from, m, to);
    };
    for (std::size_t i = 0; i < rows; ++i) copy_row(f_.u.data() + i * m, u + i * width_);
    for (std::size_t i = 0; i < cols; ++i) copy_row(f_.v.data() + i * m, v + i * width_);
    u_ = u;
    v_ = v;
    mix_.assign(3 * width_, 0.0f);
    for (std::size_t c = 0; c < 3; ++c)
        for (std::size_t j = 0; j < static_cast<std::size_t>(f_.rank); ++j) {
            if (f_.colour == FactorColour::Shared)
                mix_[c * width_ + j] = f_.colour_weights[c * f_.rank + j];
            else
                mix_[c * width_ + c * f_.rank + j] = 1.0f;  // f_'s component order (reconstruct reads it)
        }
    sampler_ = GridSampler::build(*this, sampler);
    clamped_ = 0;  // the sampler's own evaluations are not the caller's
}

std::size_t FactoredBrdf::nbytes() const {
    const std::size_t entry = f_.dtype == FactorDtype::F16 ? 2 : sizeof(float);
    return (f_.u.size() + f_.v.size()) * entry + f_.colour_weights.size() * sizeof(float);
}

std::string FactoredBrdf::describe() const {
    char warp[96] = "";
    if (f_.grid.theta_d_warp != 0.0) std::snprintf(warp, sizeof warp, ", theta_d warp %g", f_.grid.theta_d_warp);
    if (f_.grid.theta_h_warp != 0.0)
        std::snprintf(warp + std::strlen(warp), sizeof warp - std::strlen(warp), ", theta_h warp %.3g deg",
                      f_.grid.theta_h_warp * 180.0 / std::numbers::pi);
    return std::string(factor_method_name(f_.method)) + " rank " + std::to_string(f_.rank) + ", " +
           factor_space_name(f_.space) + " space, layout " + factor_layout_name(f_.layout) + ", " +
           factor_colour_name(f_.colour) + " colour, on " + f_.grid.str() + " (bin " +
           (f_.grid.position == BinPosition::Start ? "start" : "centre") +
           warp + (f_.grid.reciprocal() ? "" : std::string(", symmetry ") + symmetry_name(f_.grid.symmetry)) +
           (f_.dtype == FactorDtype::F16 ? "), float16 factors" : "), float32 factors");
}

Table FactoredBrdf::reconstruct(std::size_t* clamped) const {
    Table t(f_.grid, Table::Uninitialized{});
    const std::size_t cols = static_cast<std::size_t>(f_.columns()), m = static_cast<std::size_t>(f_.row_width());
    std::uint64_t count = 0;
    for (std::size_t bin = 0; bin < t.bins(); ++bin) {
        const float* u = f_.u.data() + bin / cols * m;
        const float* v = f_.v.data() + bin % cols * m;
        double y[3] = {0.0, 0.0, 0.0}, values[3];
        for (std::size_t j = 0; j < m; ++j) {
            const double p = static_cast<double>(u[j]) * v[j];
            for (std::size_t c = 0; c < 3; ++c) y[c] += mix_[c * width_ + j] * p;
        }
        for (int c = 0; c < 3; ++c) y[c] = std::min(y[c], ceiling_[c]);
        detail::from_space_n(f_.space, y, values, 3, count);
        t.set(bin, {values[0], values[1], values[2]});
    }
    if (clamped) *clamped = count;
    return t;
}

// Above the L2 cache (taken as 512 KiB per core), the blends' factor rows miss it
// and are prefetched a block ahead; below, the prefetches only cost instructions. So do those of a
// factor within the L1 data cache (32 KiB), which stays there: the full grid's 90 θh rows (h_dp) or
// 180 φd rows (hd_p).
constexpr std::size_t kPrefetchBytes = 512 * 1024, kL1Bytes = 32 * 1024;

Rgb FactoredBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    Rgb f;
    eval_batch(&wi, &wo, &f, 1);
    return f;
}

void FactoredBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    std::uint64_t clamped = 0;
    const bool prefetch = storage_.size() * sizeof(float) > kPrefetchBytes;
    const std::size_t row_bytes = width_ * sizeof(float);
    // The float blend is clamped in float (the ceilings lie within the float range).
    const float ceiling[3] = {static_cast<float>(ceiling_[0]), static_cast<float>(ceiling_[1]),
                              static_cast<float>(ceiling_[2])};
    const detail::FactorView view{f_.grid, width_, u_, v_, mix_.data(), ceiling,
                          prefetch && static_cast<std::size_t>(f_.rows()) * row_bytes > kL1Bytes,
                          prefetch && static_cast<std::size_t>(f_.columns()) * row_bytes > kL1Bytes,
                          grouped_channels(f_)};
    detail::eval_factors(simd_, f_.layout, view, f_.space, wi, wo, out, n, clamped);
    if (clamped) clamped_.fetch_add(clamped, std::memory_order_relaxed);
}

BrdfSample FactoredBrdf::sample_above(const Vec3& wo, double u1, double u2) const { return sampler_.sample(wo, u1, u2); }

// The compact sampler's draws take Brdf's path (blocks of draws, then the eval kernel for their weights).
// The fine sampler's: blocks of its draws (draw_block: draw()'s, bit for bit), then the eval kernel over
// the drawn pairs for their weights (its results are one call's), so each sample is sample()'s.
void FactoredBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    const HalfVectorSampler* fine = sampler_.fine();
    if (!fine) return Brdf::sample_batch(wo, u, out, n);
    constexpr std::size_t kBlock = HalfVectorSampler::kBlock;
    HalfVectorSampler::Draws d;
    Vec3 wi[kBlock], wos[kBlock];
    Rgb f[kBlock];
    std::size_t slot[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        fine->draw_block(wo + start, u + start, m, d);
        std::size_t drawn = 0;
        for (std::size_t k = 0; k < m; ++k) {
            const BrdfSample x{{d.wi_x[k], d.wi_y[k], d.wi_z[k]}, d.pdf[k], {}};
            out[start + k] = {};
            if (!usable(x)) continue;
            wi[drawn] = x.wi, wos[drawn] = wo[start + k], slot[drawn++] = start + k;
        }
        eval_batch(wi, wos, f, drawn);
        for (std::size_t j = 0; j < drawn; ++j) {
            BrdfSample& o = out[slot[j]];
            o.wi = wi[j];
            o.pdf = d.pdf[slot[j] - start];
            for (int c = 0; c < 3; ++c) o.weight[c] = f[j][c] * o.wi.z / o.pdf;  // Brdf::sample's arithmetic
        }
    }
}

double FactoredBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const { return sampler_.pdf(wo, wi); }

}  // namespace brdfz
