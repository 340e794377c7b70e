// TabularBrdf: a Brdf backed by a Rusinkiewicz Table (MERL's 90x90x180 or any other resolution).
#pragma once

#include <string>

#include "brdfz/brdf.h"
#include "brdfz/sample/halfvector.h"
#include "brdfz/sample/lazy.h"
#include "brdfz/table.h"

namespace brdfz {

enum class Lookup {
    Nearest,  // the bin MERL's published lookup picks, bit for bit
    Linear,   // multilinear over the 8 surrounding samples, skipping invalid ones (φd periodic)
};

Lookup parse_lookup(const std::string& name);  // "nearest" | "linear"; ValueError otherwise
const char* lookup_name(Lookup lookup);

class TabularBrdf final : public Brdf {
public:
    explicit TabularBrdf(Table table, Lookup lookup = Lookup::Linear);

    const Table& table() const { return table_; }
    Lookup lookup() const { return lookup_; }
    void set_lookup(Lookup lookup) {
        lookup_ = lookup;
        sampler_.reset();  // built from eval, which depends on the lookup
    }
    // The importance sampler, built from the table on first use.
    const HalfVectorSampler& sampler() const;

    int channels() const override { return 3; }
    std::size_t nbytes() const override { return table_.bins() * 3 * sizeof(float); }
    std::string describe() const override;
    bool reciprocal() const override { return table_.grid().reciprocal(); }
    const GridSpec* grid() const override { return &table_.grid(); }
    const Table* stored_table() const override { return &table_; }

protected:
    Rgb eval_above(const Vec3& wi, const Vec3& wo) const override;
    void eval_batch(const Vec3* wi, const Vec3* wo, Rgb* out, std::size_t n) const override;
    BrdfSample sample_above(const Vec3& wo, double u1, double u2) const override;
    void sample_batch(const Vec3* wo, const std::array<double, 2>* u, BrdfSample* out, std::size_t n) const override;
    double pdf_above(const Vec3& wo, const Vec3& wi) const override;

private:
    Table table_;
    Lookup lookup_;
    Lazy<HalfVectorSampler> sampler_;
};

}  // namespace brdfz
