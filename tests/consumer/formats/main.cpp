// Writes a compressed material to a .brdfz file and reads it back, without brdfz::fit: exit 0 when it
// evaluates as the source and the kinds and candidates offered leave out `analytic`.
#include <brdfz/compress.h>
#include <brdfz/errors.h>
#include <brdfz/formats/io.h>
#include <brdfz/repr/analytic/coated_diffuse.h>
#include <brdfz/select.h>

#include <cmath>
#include <cstdio>
#include <filesystem>

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    const std::string path = (std::filesystem::path(argv[1]) / "consumer.brdfz").string();
    const brdfz::CoatedDiffuse material;
    const brdfz::Compressed table = brdfz::compress(material, "tabular:res=32x32x64");
    brdfz::save(*table.brdf, path);
    const brdfz::Loaded loaded = brdfz::load(path);
    const brdfz::Vec3 wi{0.0, 0.6, 0.8}, wo{0.0, -0.6, 0.8};
    const double a = material.eval(wi, wo)[0], b = loaded.brdf->eval(wi, wo)[0];
    std::printf("analytic %.6g, .brdfz table %.6g\n", a, b);
    if (!(std::fabs(a - b) < 0.05 * a)) return 1;
    if (brdfz::find_representation_kind("analytic")) return 1;
    for (const std::string& spec : brdfz::default_candidates())
        if (spec.rfind("analytic:", 0) == 0) return 1;
    try {
        brdfz::compress(material, "analytic:lambert");
    } catch (const brdfz::SpecError& e) {
        std::printf("without brdfz::fit: %s\n", e.what());
        return 0;
    }
    return 1;
}
