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
    Linear,   // multilinear over the 8 surrounding samples, skipping invalid ones (φd periodic; bilateral: reflected)
};

Lookup parse_lookup(const std::string& name);  // "nearest" | "linear"; ValueError otherwise
const char* lookup_name(Lookup lookup);

// What every table kind shares (float32 here, compact_table.h's codes): the lookup, and the
// importance sampler, built from eval on first use and dropped when the lookup changes.
class LookupTableBrdf : public Brdf {
public:
    Lookup lookup() const { return lookup_; }
    void set_lookup(Lookup lookup) {
        lookup_ = lookup;
        sampler_.reset();
    }
    const HalfVectorSampler& sampler() const;

    int channels() const override { return 3; }
    bool reciprocal() const override { return grid()->reciprocal(); }
    bool bilateral() const override { return grid()->bilateral(); }

protected:
    explicit LookupTableBrdf(Lookup lookup) : lookup_(lookup) {}

private:
    Lookup lookup_;
    Lazy<HalfVectorSampler> sampler_;
};

class TabularBrdf final : public LookupTableBrdf {
public:
    explicit TabularBrdf(Table table, Lookup lookup = Lookup::Linear);

    const Table& table() const { return table_; }
    std::size_t nbytes() const override { return table_.bins() * 3 * sizeof(float); }
    std::string describe() const override;
    const GridSpec* grid() const override { return &table_.grid(); }
    const Table* stored_table() const override { return &table_; }

protected:
    BRDFZ_BRDF_KERNELS;

private:
    Table table_;
};

}  // namespace brdfz
