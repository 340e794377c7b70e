// Tabulates the built-in material, writes and reads a MERL table, evaluates it, and fits the table
// with the `analytic` kind that brdfz::fit registers: exit 0 when the installed headers and libraries
// work together.
#include <brdfz/compress.h>
#include <brdfz/formats/io.h>
#include <brdfz/repr/analytic/coated_diffuse.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    const std::string path = (std::filesystem::path(argv[1]) / "consumer.binary").string();
    const brdfz::CoatedDiffuse material;
    brdfz::SaveOptions options;
    options.grid = brdfz::GridSpec{32, 32, 64};
    brdfz::save(material, path, options);
    const brdfz::Loaded table = brdfz::load(path);
    const brdfz::Vec3 wi{0.0, 0.6, 0.8}, wo{0.0, -0.6, 0.8};
    const double a = material.eval(wi, wo)[0], b = table.brdf->eval(wi, wo)[0];
    std::printf("analytic %.6g, table %.6g\n", a, b);
    if (!(std::fabs(a - b) < 0.05 * a)) return 1;
    // A static brdfz::fit registers its kinds only if the link keeps its registration.
    const brdfz::Compressed fitted = brdfz::compress(*table.brdf, "analytic:lambert,starts=1");
    const double c = fitted.brdf->eval(wi, wo)[0];
    std::printf("%s: %.6g\n", fitted.brdf->describe().c_str(), c);
    return std::fabs(c - b) < 0.5 * b ? 0 : 1;
}
