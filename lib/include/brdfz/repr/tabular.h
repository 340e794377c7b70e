// TabularBrdf: a Brdf backed by a Rusinkiewicz Table (MERL's 90x90x180 or any other resolution).
#pragma once

#include <string>

#include "brdfz/brdf.h"
#include "brdfz/sample/grid_sampler.h"
#include "brdfz/table.h"

namespace brdfz {

enum class Lookup {
    Nearest,  // the bin MERL's published lookup picks, bit for bit
    Linear,   // multilinear over the 8 surrounding samples, skipping invalid ones (φd periodic; bilateral: reflected)
};

Lookup parse_lookup(const std::string& name);  // "nearest" | "linear"; ValueError otherwise
const char* lookup_name(Lookup lookup);

// What every table kind shares (float32 here, compact_table.h's codes): the lookup, and the
// importance sampler (sample/grid_sampler.h), built from eval with the table and rebuilt (of the same
// kind) when the lookup changes.
class LookupTableBrdf : public Brdf {
public:
    Lookup lookup() const { return lookup_; }
    // Not thread-safe against concurrent use of the table: it rebuilds the sampler.
    void set_lookup(Lookup lookup);
    const GridSampler& sampler() const { return sampler_; }

    int channels() const override { return 3; }
    bool reciprocal() const override { return grid()->reciprocal(); }
    bool bilateral() const override { return grid()->bilateral(); }

protected:
    explicit LookupTableBrdf(Lookup lookup) : lookup_(lookup) {}
    // The final classes call one of these at the end of their constructors, when eval works.
    void build_sampler(SamplerKind kind) { sampler_ = GridSampler::build(*this, kind); }
    void set_sampler(GridSampler sampler) { sampler_ = std::move(sampler); }
    // The kernels' shared parts: the compact sampler's draws take Brdf's path (the weight from the eval
    // kernel), the fine one's are fused with the lookup (detail/table_sample.h).
    BrdfSample sample_compact(const Vec3& wo, double u1, double u2) const { return sampler_.sample(wo, u1, u2); }
    double pdf_above(const Vec3& wo, const Vec3& wi) const override { return sampler_.pdf(wo, wi); }

private:
    Lookup lookup_;
    GridSampler sampler_;
};

class TabularBrdf final : public LookupTableBrdf {
public:
    // Builds the sampler of that kind (compact unless asked otherwise).
    explicit TabularBrdf(Table table, Lookup lookup = Lookup::Linear, SamplerKind sampler = SamplerKind::Compact);
    // With a stored compact sampler (a container's).
    TabularBrdf(Table table, Lookup lookup, CompactSampler sampler);

    const Table& table() const { return table_; }
    std::size_t nbytes() const override { return table_.bins() * 3 * sizeof(float); }
    std::string describe() const override;
    const GridSpec* grid() const override { return &table_.grid(); }
    const Table* stored_table() const override { return &table_; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override;
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override;
    void sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const override;

private:
    Table table_;
};

}  // namespace brdfz
