// brdfz eval FILE --wi x,y,z --wo x,y,z | --pairs PAIRS.csv
// Prints f (no cosine) as one "r,g,b" row per pair, full precision, in input order. All input is
// parsed before anything is printed, so a bad row produces an error and no partial output.
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <sstream>

#include "brdfz/errors.h"
#include "commands.h"
#include "output.h"

namespace brdfz::cli {
namespace {

// A header is a first row without a single numeric field ("wix,wiy,..."); a row with one (7 or 5
// columns, ';' separators, an empty cell, "1e") is a malformed data row, refused so that output rows
// stay in line with input rows.
bool is_header(const std::string& line) {
    const char* p = line.c_str();
    while (*p) {
        p += std::strspn(p, ",; \t\r");
        if (!*p) break;
        char* end = nullptr;
        std::strtod(p, &end);
        if (end != p) return false;
        p += std::strcspn(p, ",; \t\r");
    }
    return true;
}

void read_pairs(const std::string& path, std::vector<Vec3>& wi, std::vector<Vec3>& wo) {
    std::ifstream in(path);
    if (!in) throw IoError(path, "cannot open");
    std::string line;
    bool first = true;
    for (int lineno = 1; std::getline(in, line); ++lineno) {
        if (lineno == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);  // a UTF-8 byte order mark
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        const std::string where = path + ":" + std::to_string(lineno);
        double v[6];
        if (!parse_numbers(line, v, 6)) {
            if (first && is_header(line)) {
                first = false;
                continue;
            }
            throw FormatError(where, "expected 6 comma-separated numbers wix,wiy,wiz,wox,woy,woz");
        }
        first = false;
        wi.push_back(unit_direction(v, where));
        wo.push_back(unit_direction(v + 3, where));
    }
    if (in.bad()) throw IoError(path, "read failed");
}

}  // namespace

void add_eval(CLI::App& app) {
    struct Args {
        std::string file, wi, wo, pairs;
        LoadOptions load;
    };
    auto args = std::make_shared<Args>();
    CLI::App* cmd = app.add_subcommand("eval", "evaluate f (no cosine) at direction pairs; prints r,g,b per pair");
    cmd->add_option("FILE", args->file, "input file")->required();
    auto* wi = cmd->add_option("--wi", args->wi, "incident direction x,y,z (normalised)");
    auto* wo = cmd->add_option("--wo", args->wo, "outgoing direction x,y,z (normalised)");
    auto* pairs = cmd->add_option("--pairs", args->pairs, "CSV of wix,wiy,wiz,wox,woy,woz rows (header optional)");
    wi->needs(wo);
    wo->needs(wi);
    pairs->excludes(wi)->excludes(wo);
    add_load_options(cmd, args->load);
    cmd->callback([args] {
        std::vector<Vec3> wi, wo;
        if (!args->pairs.empty()) {
            read_pairs(args->pairs, wi, wo);
        } else if (!args->wi.empty()) {
            wi.push_back(parse_direction(args->wi, "--wi"));
            wo.push_back(parse_direction(args->wo, "--wo"));
        } else {
            throw ValueError("eval: give --wi and --wo, or --pairs");
        }
        const Loaded loaded = load(args->file, args->load);
        std::vector<Rgb> f(wi.size());
        loaded.brdf->eval(wi, wo, f);
        std::string out;
        out.reserve(f.size() * 64);
        for (const Rgb& v : f) out += number(v[0]) + "," + number(v[1]) + "," + number(v[2]) + "\n";
        std::cout << out;
    });
}

}  // namespace brdfz::cli
