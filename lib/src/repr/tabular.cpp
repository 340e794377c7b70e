#include "brdfz/repr/tabular.h"

#include <memory>

#include "brdfz/errors.h"
#include "detail/table_lookup.h"
#include "detail/table_sample.h"

namespace brdfz {
namespace {

// Table's float32 values, read as they are.
struct Float32Values {
    const float* data;
    void load(std::size_t bin, float v[3]) const {
        const float* p = data + 3 * bin;
        v[0] = p[0], v[1] = p[1], v[2] = p[2];
    }
    const float* floats(std::size_t bin) const { return data + 3 * bin; }  // readable as four (Table)
    const void* address(std::size_t bin) const { return data + 3 * bin; }
};

}  // namespace

Lookup parse_lookup(const std::string& name) {
    if (name == "nearest") return Lookup::Nearest;
    if (name == "linear") return Lookup::Linear;
    throw ValueError("unknown lookup '" + name + "' (expected nearest or linear)");
}

const char* lookup_name(Lookup lookup) { return lookup == Lookup::Nearest ? "nearest" : "linear"; }

TabularBrdf::TabularBrdf(Table table, Lookup lookup) : LookupTableBrdf(lookup), table_(std::move(table)) {}

std::string TabularBrdf::describe() const {
    const GridSpec& g = table_.grid();
    return detail::table_shape(g) + " float32, bin " + (g.position == BinPosition::Start ? "start" : "centre") + ", " +
           lookup_name(lookup()) + " lookup";
}

Rgb TabularBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    return detail::eval_table(table_.grid(), Float32Values{table_.data()}, lookup(), wi, wo);
}

void TabularBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    detail::eval_table_batch(table_.grid(), Float32Values{table_.data()}, lookup(), wi, wo, out, n);
}

const HalfVectorSampler& LookupTableBrdf::sampler() const {
    return sampler_.get([this] { return std::make_unique<HalfVectorSampler>(*this); });
}

// The weight comes with the draw (detail/table_sample.h), so sample() does not evaluate it again.
BrdfSample TabularBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    return detail::sample_table(table_.grid(), Float32Values{table_.data()}, lookup(), sampler(), wo, u1, u2);
}

void TabularBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    detail::sample_table_batch(table_.grid(), Float32Values{table_.data()}, lookup(), sampler(), wo, u, out, n);
}

double TabularBrdf::pdf_above(const Vec3& wo, const Vec3& wi) const { return sampler().pdf(wo, wi); }

}  // namespace brdfz
