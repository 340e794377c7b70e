// Tabulates the built-in material, writes and reads a MERL table, evaluates it: exit 0 when the
// installed headers and library work together.
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
    return std::fabs(a - b) < 0.05 * a ? 0 : 1;
}
