#include "brdfz/repr/tabular.h"

#include <memory>

#include "brdfz/errors.h"
#include "detail/table_lookup.h"
#include "repr/table_kernels.h"

namespace brdfz {

Lookup parse_lookup(const std::string& name) {
    if (name == "nearest") return Lookup::Nearest;
    if (name == "linear") return Lookup::Linear;
    throw ValueError("unknown lookup '" + name + "' (expected nearest or linear)");
}

const char* lookup_name(Lookup lookup) { return lookup == Lookup::Nearest ? "nearest" : "linear"; }

void LookupTableBrdf::set_lookup(Lookup lookup) {
    lookup_ = lookup;
    build_sampler(sampler_.kind());
}

TabularBrdf::TabularBrdf(Table table, Lookup lookup, SamplerKind sampler)
    : LookupTableBrdf(lookup), table_(std::move(table)) {
    build_sampler(sampler);
}

TabularBrdf::TabularBrdf(Table table, Lookup lookup, CompactSampler sampler)
    : LookupTableBrdf(lookup), table_(std::move(table)) {
    set_sampler(GridSampler(std::move(sampler)));
}

std::string TabularBrdf::describe() const {
    const GridSpec& g = table_.grid();
    return detail::table_shape(g) + " float32, bin " + (g.position == BinPosition::Start ? "start" : "centre") + ", " +
           lookup_name(lookup()) + " lookup";
}

Rgb TabularBrdf::eval_above(const Vec3& wi, const Vec3& wo) const {
    return detail::eval_table(table_.grid(), detail::TableFloat32Values{{table_.data()}}, lookup(), wi, wo);
}

void TabularBrdf::eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const {
    detail::eval_table_batch(table_.grid(), detail::TableFloat32Values{{table_.data()}}, lookup(), wi, wo, out, n);
}

// The fine sampler's weight comes with the draw (detail/table_sample.h), so sample() does not evaluate
// it again; the compact sampler's is the eval kernel's (Brdf::sample, Brdf::sample_batch).
BrdfSample TabularBrdf::sample_above(const Vec3& wo, double u1, double u2) const {
    if (const HalfVectorSampler* fine = sampler().fine())
        return detail::sample_table(table_.grid(), detail::TableFloat32Values{{table_.data()}}, lookup(), *fine, wo, u1, u2);
    return sample_compact(wo, u1, u2);
}

void TabularBrdf::sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const {
    if (const HalfVectorSampler* fine = sampler().fine())
        return detail::sample_table_batch(table_.grid(), detail::TableFloat32Values{{table_.data()}}, lookup(), *fine, wo, u, out, n);
    Brdf::sample_batch(wo, u, out, n);
}

}  // namespace brdfz
