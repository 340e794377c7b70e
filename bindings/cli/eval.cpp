// brdfz eval FILE --wi x,y,z --wo x,y,z | --pairs PAIRS.csv
// Prints f (no cosine) as one "r,g,b" row per pair, full precision, in input order, a block of rows at
// a time, so that memory does not grow with the number of pairs. Every row of a pairs file is checked
// before anything is printed, so a bad row produces an error and no partial output; pairs from a pipe
// are read once, and a bad row there ends the output at the rows before it.
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>

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

// Rows of PAIRS.csv, kBlock at a time: block(wi, wo) for each run of rows, in order. FormatError
// naming the line for a malformed row, IoError when the file cannot be read.
constexpr std::size_t kBlock = 1 << 16;
using Block = std::function<void(const std::vector<Vec3>& wi, const std::vector<Vec3>& wo)>;

void read_pairs(const std::string& path, const Block& block) {
    std::ifstream in(path);
    if (!in) throw IoError(path, "cannot open");
    std::vector<Vec3> wi, wo;
    wi.reserve(kBlock);
    wo.reserve(kBlock);
    std::string line;
    bool first = true;
    for (std::size_t lineno = 1; std::getline(in, line); ++lineno) {
        if (lineno == 1 && line.starts_with("\xEF\xBB\xBF")) line.erase(0, 3);  // a UTF-8 byte order mark
        if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
        double v[6];
        if (!parse_numbers(line, v, 6)) {
            if (first && is_header(line)) {
                first = false;
                continue;
            }
            throw FormatError(path + ":" + std::to_string(lineno), "expected 6 comma-separated numbers wix,wiy,wiz,wox,woy,woz");
        }
        first = false;
        Vec3 a, b;
        if (!to_unit(v, a) || !to_unit(v + 3, b)) {
            // The line's name is made for the error only: for every row it would cost more than the row.
            const std::string where = path + ":" + std::to_string(lineno);
            unit_direction(v, where);
            unit_direction(v + 3, where);
        }
        wi.push_back(a);
        wo.push_back(b);
        if (wi.size() == kBlock) {
            block(wi, wo);
            wi.clear();
            wo.clear();
        }
    }
    if (in.bad()) throw IoError(path, "read failed");
    if (!wi.empty()) block(wi, wo);
}

// f at each pair as "r,g,b" rows on stdout.
void print(const Brdf& brdf, const std::vector<Vec3>& wi, const std::vector<Vec3>& wo) {
    std::vector<Rgb> f(wi.size());
    brdf.eval(wi, wo, f);
    std::string out;
    out.reserve(f.size() * 64);
    for (const Rgb& v : f) {
        append_number(out, v[0]);
        out += ',';
        append_number(out, v[1]);
        out += ',';
        append_number(out, v[2]);
        out += '\n';
    }
    std::cout << out;
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
        if (!args->pairs.empty()) {
            // A file is read twice, once to check every row and once to evaluate them, so that a bad
            // row prints nothing and memory stays bounded; a pipe is read once, printing as it goes.
            const bool regular = std::filesystem::is_regular_file(args->pairs);
            if (regular) read_pairs(args->pairs, [](const auto&, const auto&) {});
            const Loaded loaded = load(args->file, args->load);
            read_pairs(args->pairs, [&](const std::vector<Vec3>& wi, const std::vector<Vec3>& wo) {
                print(*loaded.brdf, wi, wo);
            });
        } else if (!args->wi.empty()) {
            const Vec3 wi = parse_direction(args->wi, "--wi"), wo = parse_direction(args->wo, "--wo");
            print(*load(args->file, args->load).brdf, {wi}, {wo});
        } else {
            throw ValueError("eval: give --wi and --wo, or --pairs");
        }
        std::cout << std::flush;
        if (!std::cout) throw IoError("<stdout>", "write failed");
    });
}

}  // namespace brdfz::cli
