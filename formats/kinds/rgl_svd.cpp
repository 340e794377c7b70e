// Kind `rgl_svd`: an isotropic RGL-EPFL material in its own parameterisation, its rgb tensor a
// weighted low-rank product in float16 or int8 (brdfz/formats/rgl_svd.h).
#include "brdfz/compress.h"
#include "brdfz/errors.h"
#include "brdfz/formats/rgl_svd.h"

namespace brdfz::kinds {
namespace {

bool applies(const Brdf& source) {
    const auto* file = dynamic_cast<const rgl::RglBrdf*>(&source);
    return file && !file->svd() && rgl::vndf_is_derived(file->tensors());
}

Compressed build(const Brdf& source, const ReprSpec& spec, const CompressOptions&) {
    const int rank = spec.get_int("rank", 22, 1, static_cast<int>(rgl::kMaxSvdRank));
    const double weight = spec.get_double("weight", 1.0);
    const auto dtype = spec.get_choice("dtype", "f16", {"f16", "i8"}) == "i8" ? rgl::SvdDtype::I8 : rgl::SvdDtype::F16;
    spec.finish();
    if (!applies(source))
        throw ValueError("rgl_svd: the source must be an isotropic RGL-EPFL measurement (a .bsdf file or its .brdfz "
                         "conversion, its vndf derived from its ndf), not " + source.describe());
    Compressed out;
    const auto& file = dynamic_cast<const rgl::RglBrdf&>(source);
    out.brdf = rgl::make_svd_brdf(rgl::factor(file.tensors(), static_cast<std::size_t>(rank), weight, dtype));
    return out;
}

}  // namespace

void register_rgl_svd(std::vector<ReprKind>& out) {
    out.push_back({"rgl_svd",
                   "an RGL-EPFL material in its own parameterisation (grids placed by its measured microfacet "
                   "distribution), the rgb tensor a rank-K product in float16 or int8; RGL sources only",
                   "",
                   {{"rank", "22", "factor rank K, 1-96 (at most 3 x the rgb grid's rows)"},
                    {"weight", "1", "in [0, 4]: the power of the microfacet distribution in the fit's weights (0: "
                                    "solid angle and cosines only)"},
                    {"dtype", "f16", "f16|i8: stored factors (i8: int8 codes, a float16 step per slice or channel in each factor; about half the bytes)"}},
                   build,
                   nullptr,
                   applies});
}

}  // namespace brdfz::kinds
