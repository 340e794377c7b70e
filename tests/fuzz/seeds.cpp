// Writes the seed corpus for the fuzz harnesses: small valid files of every format, made by the
// library's own writers where there is one (no shared data is used or committed).
// Usage: fuzz_seeds DIR  ->  DIR/<harness>/<seed files>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>

#include "brdfz/formats/container.h"
#include "brdfz/formats/exr.h"
#include "brdfz/formats/merl.h"
#include "brdfz/formats/model_json.h"
#include "brdfz/formats/rgl.h"
#include "brdfz/formats/rgl_writer.h"
#include "brdfz/repr/analytic/coated_diffuse.h"
#include "brdfz/repr/tabular.h"

namespace fs = std::filesystem;
using namespace brdfz;

namespace {

Table small_table(GridSpec g) {
    Table t(g);
    for (std::size_t k = 0; k < t.bins(); ++k) t.set(k, {0.1 + 0.01 * k, 0.2, 0.3 + 0.02 * (k % 3)});
    t.invalidate(0);
    return t;
}

void text(const fs::path& p, const char* s) { std::ofstream(p) << s; }

}  // namespace

int main(int argc, char** argv) try {
    if (argc != 2) {
        std::fprintf(stderr, "usage: fuzz_seeds DIR\n");
        return 2;
    }
    const fs::path dir = argv[1];
    for (const char* h : {"merl", "rgl", "container", "exr", "cornell", "alta", "json"}) fs::create_directories(dir / h);

    merl::write((dir / "merl" / "a.binary").string(), small_table({2, 2, 2}));
    merl::write((dir / "merl" / "b.binary").string(), small_table({3, 1, 5}));

    exr::write((dir / "exr" / "a.exr").string(), small_table({2, 2, 2}));
    exr::write((dir / "exr" / "b.exr").string(), small_table({3, 2, 5, BinPosition::Start}));

    container::write((dir / "container" / "tabular.brdfz").string(), TabularBrdf(small_table({2, 3, 4})));
    container::WriteOptions coarse;
    coarse.grid = GridSpec{2, 2, 2};
    container::write((dir / "container" / "tabulated.brdfz").string(), CoatedDiffuse(), coarse);

    // A small RGL file: the RGL writer's parameterisation of a built-in material, as a .bsdf and as
    // the container's RGL storage.
    rgl::WriteOptions w;
    w.n_theta_i = 3;
    w.vndf_resolution = 4;
    w.rgb_resolution = 4;
    w.ndf_resolution = 4;
    const std::string bsdf = (dir / "rgl" / "a.bsdf").string();
    rgl::write(bsdf, CoatedDiffuse(), w);
    container::write((dir / "container" / "rgl.brdfz").string(), *rgl::read(bsdf).brdf);

    text(dir / "cornell" / "a.brdf",
         "# Cornell-style test file\n3\n400 550 700\n"
         "0.1 0 0.2 3.1 0.5 0.6 0.7\n0.3 0.5 0.3 3.6 0.4 0.45 0.5\n1.0 0 0.9 3.14 0.9 0.8 0.7\n");
    text(dir / "alta" / "a.dat",
         "#DIM 3 1\n#PARAM_IN ISOTROPIC_TL_TV_PROJ_DPHI\n#PARAM_OUT INV_STERADIAN\n#VS 0\n#ALTA HEADER END\n"
         "0.1 0.2 0.3 0.5\n0.2 0.1 -0.1 0.7\n0.5 0.0 0.0 2.5\n");
    text(dir / "alta" / "b.dat", "#DIM 3 1\n#PARAM_IN RUSIN_TH_TD_PD\n0.1 0.2 0.3 0.5\n0.4 0.1 1.2 0.2\n");
    text(dir / "alta" / "c.dat",
         "#DIM 6 3\n#PARAM_IN CARTESIAN\n#PARAM_OUT INV_STERADIAN_COSINE_FACTOR\n#VS 1\n"
         "0 0 1 0.6 0 0.8 0.1 0.2 0.3 0.01\n0.3 0.4 0.866 0 0 1 0.4 0.5 0.6 0.02\n");
    text(dir / "alta" / "d.dat", "#DIM 4 3\n#PARAM_IN SPHERICAL_TL_PL_TV_PV\n#PARAM_OUT RGB_COLOR\n0.4 1 0.9 -2 0.1 0.2 0.3\n");
    text(dir / "json" / "a.json",
         "{\"format\": \"brdfz-analytic\", \"version\": 1, \"model\": \"lambert+ggx\", \"parameters\": "
         "{\"lambert.rho_r\": 0.1, \"lambert.rho_g\": 0.2, \"lambert.rho_b\": 0.3, \"ggx.ks_r\": 1, \"ggx.ks_g\": 1, "
         "\"ggx.ks_b\": 1, \"ggx.alpha\": 0.1, \"ggx.f0\": 0.04}, \"provenance\": {\"source\": \"seed\"}}\n");
    text(dir / "json" / "scene.json",
         "{\"format\": \"brdfz-scene\", \"version\": 1, \"name\": \"s\", \"seed\": 3, \"views\": [{\"axis\": [0, 0, 1], "
         "\"max_angle_deg\": 20, \"count\": 4}], \"lights\": [{\"direction\": [0, 0.1, 1], \"spread_deg\": 2, "
         "\"intensity\": 1, \"samples\": 2}], \"environment\": {\"radiance\": 0.1, \"samples\": 4}, "
         "\"pairs\": [{\"wi\": [0, 0.5, 1], \"wo\": [0, -0.5, 1], \"weight\": 2}]}\n");
    return 0;
} catch (const std::exception& e) {
    std::fprintf(stderr, "fuzz_seeds: %s\n", e.what());
    return 1;
}
