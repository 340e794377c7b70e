// Compresses the built-in material into a factorisation and evaluates it, with brdfz::core alone:
// exit 0 when it evaluates as the source.
#include <brdfz/compress.h>
#include <brdfz/repr/analytic/coated_diffuse.h>

#include <cmath>
#include <cstdio>

int main() {
    const brdfz::CoatedDiffuse material;
    const brdfz::Compressed svd = brdfz::compress(material, "svd:rank=4,res=32x32x64");
    const brdfz::Vec3 wi{0.0, 0.6, 0.8}, wo{0.0, -0.6, 0.8};
    const double a = material.eval(wi, wo)[0], b = svd.brdf->eval(wi, wo)[0];
    std::printf("analytic %.6g, %s %.6g\n", a, svd.brdf->describe().c_str(), b);
    return std::fabs(a - b) < 0.05 * a ? 0 : 1;
}
