// Analytic models: a sum of lobes named by a string, with one flat parameter vector.
//
// Model strings: terms joined by '+', each a lobe family name (catalogue.h) optionally followed by a
// repeat count: "lambert+ggx", "lambert+ggx+ggx", "lafortune3" (= three Lafortune lobes). Parameters
// are stored term by term in the family's order and named "<term>.<param>", where <term> is the family
// name, numbered from 1 when the family occurs more than once: "lambert.rho_r", "ggx2.alpha".
#pragma once

#include <cstddef>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "brdfz/brdf.h"
#include "brdfz/repr/analytic/lobe.h"
#include "brdfz/sample/compact.h"
#include "brdfz/sample/lobes.h"

namespace brdfz {

class Model {
public:
    struct Term {
        const LobeType* type;
        std::size_t offset;  // index of its first parameter
        std::string label;   // "ggx", or "ggx2" when repeated
    };

    static constexpr std::size_t kMaxTerms = runtime::kernels::kMaxLobeTerms;  // what the runtime samples

    // ValueError naming the problem (unknown lobe, bad count, empty term).
    static Model parse(std::string_view text);

    const std::string& text() const { return text_; }
    std::span<const Term> terms() const { return terms_; }
    std::size_t size() const { return specs_.size(); }  // number of parameters
    const ParamSpec& spec(std::size_t i) const { return specs_[i]; }
    const std::string& name(std::size_t i) const { return names_[i]; }
    // Index of a parameter by full name, or size() if there is none.
    std::size_t find(std::string_view name) const;
    std::vector<double> defaults() const;
    // ValueError unless `params` holds size() finite values inside their bounds; names the first bad one.
    void validate(std::span<const double> params) const;

private:
    std::string text_;
    std::vector<Term> terms_;
    std::vector<ParamSpec> specs_;
    std::vector<std::string> names_;
};

// Comma-separated names of every lobe family, for help and error messages.
std::string lobe_family_names();

// Sampled by its lobe mixture (sample/lobes.h: no data beyond the parameters) or, as the kind
// `analytic` does by default (sampler=compact), by the compact sampler of the gridded kinds
// (sample/compact.h: 14.7 KB of CDFs built from eval), whose weights vary less where the lobes' own
// samplers follow f·cosθi loosely (rough lobes at grazing views, a Fresnel term, coloured lobes).
class AnalyticBrdf final : public Brdf {
public:
    // Validates the parameters (Model::validate). Samples by the lobe mixture.
    AnalyticBrdf(Model model, std::vector<double> params);
    AnalyticBrdf(std::string_view model, std::vector<double> params) : AnalyticBrdf(Model::parse(model), std::move(params)) {}
    // Samples by `compact`: built from this model (CompactSampler(brdf)) or stored with it.
    AnalyticBrdf(Model model, std::vector<double> params, CompactSampler compact);
    // This model sampled by a compact sampler built from its eval now.
    static std::unique_ptr<AnalyticBrdf> with_compact_sampler(Model model, std::vector<double> params,
                                                              const CompactSamplerOptions& options = {});

    const Model& model() const { return model_; }
    std::span<const double> params() const { return params_; }
    // The lobe mixture (sample/lobes.h), built with the model (copies share it): its eval, and its
    // sampler unless a compact one is attached (then without its albedo table: LobeMixture).
    const LobeMixture& sampler() const { return *sampler_; }
    // The compact sampler, or null when the lobe mixture samples.
    const CompactSampler* compact_sampler() const { return compact_.get(); }

    int channels() const override { return 3; }
    std::size_t nbytes() const override { return params_.size() * sizeof(double); }
    std::string describe() const override;

protected:
    BRDFZ_BRDF_KERNELS;

private:
    Model model_;
    std::vector<double> params_;
    std::shared_ptr<const LobeMixture> sampler_;
    std::shared_ptr<const CompactSampler> compact_;
};

}  // namespace brdfz
