#include "brdfz/repr/analytic/model.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <memory>

#include "brdfz/errors.h"
#include "brdfz/repr/analytic/catalogue.h"

namespace brdfz {
namespace {

std::string_view trim(std::string_view s) {
    const auto b = s.find_first_not_of(" \t");
    if (b == std::string_view::npos) return {};
    return s.substr(b, s.find_last_not_of(" \t") - b + 1);
}

}  // namespace

std::string lobe_family_names() {
    std::string out;
    for (const LobeType& t : lobe_types()) out += (out.empty() ? "" : ", ") + std::string(t.name);
    return out;
}

Model Model::parse(std::string_view text) {
    Model m;
    m.text_ = std::string(trim(text));
    if (m.text_.empty()) throw ValueError("model: empty model string");
    std::vector<int> types;
    std::string_view rest = m.text_;
    while (true) {
        const std::size_t plus = rest.find('+');
        const std::string_view term = trim(rest.substr(0, plus));
        if (term.empty()) throw ValueError("model '" + m.text_ + "': empty term");
        // Trailing digits are a repeat count: "lafortune3".
        std::size_t digits = term.size();
        while (digits > 0 && term[digits - 1] >= '0' && term[digits - 1] <= '9') --digits;
        const std::string_view family = term.substr(0, digits);
        int count = 1;
        if (digits < term.size()) {
            const auto [end, ec] = std::from_chars(term.data() + digits, term.data() + term.size(), count);
            if (ec != std::errc() || count < 1 || count > static_cast<int>(kMaxTerms))
                throw ValueError("model '" + m.text_ + "': bad repeat count in '" + std::string(term) + "'");
        }
        const int type = find_lobe_type(family);
        if (type < 0)
            throw ValueError("model '" + m.text_ + "': unknown lobe '" + std::string(family) + "' (known: " +
                             lobe_family_names() + ")");
        for (int k = 0; k < count; ++k) types.push_back(type);
        if (types.size() > kMaxTerms)
            throw ValueError("model '" + m.text_ + "': more than " + std::to_string(kMaxTerms) + " lobes");
        if (plus == std::string_view::npos) break;
        rest = rest.substr(plus + 1);
    }
    for (std::size_t i = 0; i < types.size(); ++i) {
        const LobeType& t = lobe_types()[types[i]];
        const auto occurrences = std::count(types.begin(), types.end(), types[i]);
        std::string label(t.name);
        if (occurrences > 1) label += std::to_string(std::count(types.begin(), types.begin() + i + 1, types[i]));
        m.terms_.push_back({&t, m.specs_.size(), label});
        for (const ParamSpec& p : t.params) {
            m.specs_.push_back(p);
            m.names_.push_back(label + "." + std::string(p.name));
        }
    }
    return m;
}

std::size_t Model::find(std::string_view name) const {
    return static_cast<std::size_t>(std::find(names_.begin(), names_.end(), name) - names_.begin());
}

std::vector<double> Model::defaults() const {
    std::vector<double> out;
    for (const ParamSpec& p : specs_) out.push_back(p.init);
    return out;
}

void Model::validate(std::span<const double> params) const {
    if (params.size() != size())
        throw ValueError("model " + text_ + ": " + std::to_string(params.size()) + " parameters given, " +
                         std::to_string(size()) + " expected");
    for (std::size_t i = 0; i < size(); ++i) {
        const double v = params[i];
        if (!std::isfinite(v)) throw ValueError("model " + text_ + ": parameter " + names_[i] + " is not finite");
        if (v < specs_[i].lo || v > specs_[i].hi) {
            char buf[160];
            std::snprintf(buf, sizeof buf, " = %.17g is outside its bounds [%g, %g]", v, specs_[i].lo, specs_[i].hi);
            throw ValueError("model " + text_ + ": parameter " + names_[i] + buf);
        }
    }
}

AnalyticBrdf::AnalyticBrdf(Model model, std::vector<double> params) : model_(std::move(model)), params_(std::move(params)) {
    model_.validate(params_);
    sampler_ = std::make_shared<const LobeMixture>(model_, params_);
}

AnalyticBrdf::AnalyticBrdf(Model model, std::vector<double> params, CompactSampler compact)
    : model_(std::move(model)), params_(std::move(params)) {
    model_.validate(params_);
    sampler_ = std::make_shared<const LobeMixture>(model_, params_, false);
    compact_ = std::make_shared<const CompactSampler>(std::move(compact));
}

std::unique_ptr<AnalyticBrdf> AnalyticBrdf::with_compact_sampler(Model model, std::vector<double> params,
                                                                 const CompactSamplerOptions& options) {
    auto out = std::make_unique<AnalyticBrdf>(std::move(model), std::move(params));
    out->compact_ = std::make_shared<const CompactSampler>(*out, options);
    out->sampler_ = std::make_shared<const LobeMixture>(out->model_, out->params_, false);  // its table unused
    return out;
}

std::string AnalyticBrdf::describe() const {
    std::string out = "analytic " + model_.text() + ", " + std::to_string(params_.size()) + " float64 parameters:";
    for (std::size_t i = 0; i < params_.size(); ++i) {
        char buf[32];
        std::snprintf(buf, sizeof buf, "%.4g", params_[i]);
        out += " " + model_.name(i) + "=" + buf;
    }
    return out;
}

namespace {
// Directions with a NaN or infinite component evaluate to 0 (brdf.h: never NaN).
bool finite_pair(const Vec3& wi, const Vec3& wo) {
    return std::isfinite(wi.x + wi.y + wi.z + wo.x + wo.y + wo.z);
}
}  // namespace

Rgb AnalyticBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    if (!finite_pair(wi, wo)) return {0.0, 0.0, 0.0};
    Rgb f;
    runtime::kernels::lobe_mixture_eval(sampler().view(), wi, wo, f.data());
    return f;
}

void AnalyticBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    constexpr std::size_t kSize = GeometryBlock::kSize;
    GeometryBlock geo;
    alignas(64) double r[kSize], g[kSize], b[kSize];
    for (std::size_t base = 0; base < n; base += kSize) {
        const std::size_t m = std::min(kSize, n - base);
        const Vec3* __restrict i = wi + base;
        const Vec3* __restrict o = wo + base;
        for (std::size_t k = 0; k < m; ++k) {
            const Geometry<double> x = make_geometry(i[k].x, i[k].y, i[k].z, o[k].x, o[k].y, o[k].z);
            geo.ix[k] = x.ix, geo.iy[k] = x.iy, geo.iz[k] = x.iz;
            geo.ox[k] = x.ox, geo.oy[k] = x.oy, geo.oz[k] = x.oz;
            geo.hx[k] = x.hx, geo.hy[k] = x.hy, geo.hz[k] = x.hz, geo.d[k] = x.d;
            r[k] = g[k] = b[k] = 0.0;
        }
        for (const Model::Term& t : model_.terms()) t.type->accumulate(geo, m, params_.data() + t.offset, r, g, b);
        // Below the horizon (or non-finite directions) the value is 0 whatever the lobes computed there.
        for (std::size_t k = 0; k < m; ++k) {
            // Bitwise & rather than &&: no branch, so the loop vectorises.
            const bool above = (i[k].z > 0.0) & (o[k].z > 0.0) & finite_pair(i[k], o[k]);
            out[base + k] = {above ? r[k] : 0.0, above ? g[k] : 0.0, above ? b[k] : 0.0};
        }
    }
}

BrdfSample AnalyticBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    // Non-finite directions have no sample (their eval is 0).
    if (!std::isfinite(wo.x + wo.y + wo.z)) return {};
    if (compact_) return compact_->sample(wo, u1, u2);
    return sampler().sample(wo, u1, u2);
}

// The mixture's block kernel on the draws sample() makes (the others fail), then the batch eval for the
// weights: each sample is sample()'s, bit for bit. A compact sampler's draws take Brdf's path (blocks of
// draws, then the eval kernel for their weights).
void AnalyticBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    if (compact_) return Brdf::sample_batch(wo, u, out, n);
    constexpr std::size_t kBlock = 64;
    const LobeMixture& mixture = sampler();
    Vec3 views[kBlock], wi[kBlock], wos[kBlock];
    std::array<double, 2> us[kBlock];
    BrdfSample drawn[kBlock];
    Rgb f[kBlock];
    std::size_t lane[kBlock], kept[kBlock];
    for (std::size_t start = 0; start < n; start += kBlock) {
        const std::size_t m = std::min(kBlock, n - start);
        std::size_t count = 0;
        for (std::size_t k = 0; k < m; ++k) {
            const Vec3& w = wo[start + k];
            out[start + k] = {};
            if (!can_draw(w, u[start + k][0], u[start + k][1]) || !std::isfinite(w.x + w.y + w.z)) continue;
            views[count] = w, us[count] = u[start + k], lane[count++] = start + k;
        }
        mixture.sample_block(views, us, count, drawn);
        std::size_t usable_count = 0;
        for (std::size_t c = 0; c < count; ++c)
            if (usable(drawn[c])) wi[usable_count] = drawn[c].wi, wos[usable_count] = views[c], kept[usable_count++] = c;
        eval_batch(wi, wos, f, usable_count);
        for (std::size_t j = 0; j < usable_count; ++j) {
            BrdfSample& o = out[lane[kept[j]]];
            o = drawn[kept[j]];
            for (int c = 0; c < 3; ++c) o.weight[c] = f[j][c] * o.wi.z / o.pdf;  // Brdf::sample's arithmetic
        }
    }
}

double AnalyticBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const {
    if (!finite_pair(wi, wo)) return 0.0;
    if (compact_) return compact_->pdf(wo, wi);
    return sampler().pdf(wo, wi);
}

}  // namespace brdfz
