// brdfz sample FILE --wo x,y,z -n N [--seed S]: draws wi from the file's sampler and prints one CSV
// row per sample: wi, its pdf (per unit solid angle) and the weight f·cosθi/pdf. Failed samples
// (pdf 0) are printed too, so there are always N rows. Rows are written as they are drawn, a block at a
// time, so memory does not grow with N.
#include <iostream>
#include <random>

#include "brdfz/errors.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {

void add_sample(CLI::App& app) {
    struct Args {
        std::string file, wo;
        std::size_t n = 16;
        std::uint64_t seed = 1;
        LoadOptions load;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("sample", "draw incident directions from the importance sampler");
    cmd->add_option("FILE", args->file, "input file")->required();
    cmd->add_option("--wo", args->wo, "outgoing direction x,y,z (normalised)")->required();
    cmd->add_option("-n", args->n, "number of samples")->capture_default_str()->check(CLI::Range(1, 100000000));
    cmd->add_option("--seed", args->seed, "random seed")->capture_default_str()->check(unsigned_integer());
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        const Vec3 wo = parse_direction(args->wo, "--wo");
        const Loaded loaded = load(args->file, args->load);
        std::mt19937_64 rng(args->seed);
        std::uniform_real_distribution<double> u(0.0, 1.0);
        constexpr std::size_t kBlock = 4096;
        std::string out = "wix,wiy,wiz,pdf,weight_r,weight_g,weight_b\n";
        for (std::size_t k = 0; k < args->n; ++k) {
            const BrdfSample s = loaded.brdf->sample(wo, u(rng), u(rng));
            out += number(s.wi.x) + "," + number(s.wi.y) + "," + number(s.wi.z) + "," + number(s.pdf) + "," +
                   number(s.weight[0]) + "," + number(s.weight[1]) + "," + number(s.weight[2]) + "\n";
            if ((k + 1) % kBlock == 0) {
                std::cout << out;
                out.clear();
            }
        }
        std::cout << out << std::flush;
        if (!std::cout) throw IoError("<stdout>", "write failed");
    });
}

}  // namespace brdfz::cli
