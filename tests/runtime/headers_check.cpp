// Every header of brdfz::runtime, compiled alone as C++17 with every warning an error (the target
// brdfz_runtime_headers_check): the runtime promises C++17 and nothing but the standard library, and
// only its own include folder is on this unit's path.
#include "brdfz/runtime/crc32c.h"
#include "brdfz/runtime/kernels/compact_sampler.h"
#include "brdfz/runtime/kernels/factored.h"
#include "brdfz/runtime/kernels/grid.h"
#include "brdfz/runtime/kernels/lobe_mixture.h"
#include "brdfz/runtime/kernels/lobes/ashikhmin_shirley.h"
#include "brdfz/runtime/kernels/lobes/blinn_phong.h"
#include "brdfz/runtime/kernels/lobes/families.h"
#include "brdfz/runtime/kernels/lobes/lafortune.h"
#include "brdfz/runtime/kernels/lobes/lambert.h"
#include "brdfz/runtime/kernels/lobes/lobe.h"
#include "brdfz/runtime/kernels/lobes/microfacet.h"
#include "brdfz/runtime/kernels/lobes/sampling.h"
#include "brdfz/runtime/kernels/lobes/ward.h"
#include "brdfz/runtime/kernels/math.h"
#include "brdfz/runtime/kernels/phi_h.h"
#include "brdfz/runtime/kernels/simd.h"
#include "brdfz/runtime/kernels/values.h"
#include "brdfz/runtime/layout.h"
#include "brdfz/runtime/runtime.h"
#include "brdfz/runtime/vec.h"

// Templates are checked where they are instantiated: every family's eval in float (kLobeFamilies
// instantiates the double one). Never called; the unit is only compiled.
template <typename... Families>
void eval_float(brdfz::lobes::FamilyList<Families...>, const brdfz::Geometry<float>& g, const float* p, float* out) {
    (Families::eval(g, p, out), ...);
}
void brdfz_runtime_headers_check(const brdfz::Geometry<float>& g, const float* p, float* out) {
    eval_float(brdfz::lobes::AllFamilies{}, g, p, out);
}
