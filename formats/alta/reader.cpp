#include <cmath>
#include <cstddef>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/alta.h"
#include "detail/horizon.h"
#include "detail/text_scan.h"

namespace brdfz::alta {
namespace {

enum class Param { TlTvProjDphi, RusinThTdPd, RusinThTd, RusinThPhTdPd, SphericalTlPlTvPv, Cartesian };

struct ParamInfo {
    std::string_view name;
    Param param;
    std::size_t dim;
};

constexpr ParamInfo kParams[] = {
    {"ISOTROPIC_TL_TV_PROJ_DPHI", Param::TlTvProjDphi, 3},
    {"RUSIN_TH_TD_PD", Param::RusinThTdPd, 3},
    {"RUSIN_TH_TD", Param::RusinThTd, 2},
    {"RUSIN_TH_PH_TD_PD", Param::RusinThPhTdPd, 4},
    {"SPHERICAL_TL_PL_TV_PV", Param::SphericalTlPlTvPv, 4},
    {"CARTESIAN", Param::Cartesian, 6},
};

// What a row's values are (alta.h), and how many a row may hold.
struct OutputInfo {
    std::string_view name;
    bool cosine;            // f_r·cosθ of the light, divided out on reading
    bool one, three;        // the #DIM output counts it comes in
};

constexpr OutputInfo kOutputs[] = {
    {"INV_STERADIAN", false, true, true},
    {"INV_STERADIAN_COSINE_FACTOR", true, true, true},
    {"RGB_COLOR", false, false, true},
};

constexpr std::size_t kMaxDim = 16;

struct Header {
    std::size_t dim_in = 0, dim_out = 0, vs = 0;
    std::string param_in, param_out = "INV_STERADIAN", format = "text";
    bool has_dim = false, has_param_in = false, has_param_out = false, has_vs = false, has_format = false;
    const ParamInfo* param = nullptr;  // set once the header is complete
    const OutputInfo* output = nullptr;
};

template <typename Info, std::size_t N>
std::string supported_names(const Info (&list)[N]) {
    std::string s;
    for (const Info& p : list) s += (s.empty() ? "" : ", ") + std::string(p.name);
    return s;
}

// (V, L) of ALTA's Rusinkiewicz coordinates: d = (θd, φd) rotated by θh about y, then by φh about z,
// is the view; the light is its mirror image about h.
std::pair<Vec3, Vec3> rusinkiewicz(double theta_h, double phi_h, double theta_d, double phi_d) {
    const double ch = std::cos(theta_h), sh = std::sin(theta_h), cp = std::cos(phi_h), sp = std::sin(phi_h);
    const Vec3 t{ch * cp, ch * sp, -sh}, b{-sp, cp, 0.0}, h{sh * cp, sh * sp, ch};
    const Vec3 d = spherical_direction(theta_d, phi_d);
    const Vec3 v = d.x * t + d.y * b + d.z * h;
    const Vec3 l = (-d.x) * t + (-d.y) * b + d.z * h;
    return {v, l};
}

class Scanner {
public:
    Scanner(const std::string& path, std::string_view text) : path_(path), text_(text) {}

    // Walks the file: reads and checks the header, checks every row and hands its directions and
    // f_r (three channels, a monochrome value repeated) with its line number to `on_row(line, wi, wo, f)`. Run twice: once to count rows before
    // anything is allocated, once to store them. Returns the header.
    template <typename OnRow>
    Header scan(OnRow&& on_row) {
        Header h;
        bool in_header = true;
        detail::LineScanner lines(text_);
        std::string_view line;
        std::vector<double> row;
        while (lines.next(line)) {
            const std::string_view content = detail::trim_left(line);
            const std::size_t at = lines.number();
            if (content.empty()) continue;
            if (content[0] == '#') {
                const bool key = content.size() > 1 && is_letter(content[1]);
                if (in_header && key && header_line(content.substr(1), at, h)) {
                    finish(h);
                    in_header = false;
                }
                continue;
            }
            if (in_header) {
                finish(h);
                in_header = false;
            }
            parse_row(line, at, h, row);
            const auto [wi, wo] = directions(row, at, h);
            Rgb f;
            for (int c = 0; c < 3; ++c) f[c] = row[h.dim_in + (h.dim_out == 3 ? c : 0)];
            // f_r·cosθl, the light being wi: below the horizon (cosθl <= 0) the row is dropped anyway.
            if (h.output->cosine && wi.z > 0.0)
                for (double& c : f) c /= wi.z;
            on_row(at, wi, wo, f);
        }
        if (in_header) finish(h);
        return h;
    }

private:
    static bool is_letter(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }

    FormatError fail(std::size_t line, const std::string& reason) const {
        return FormatError(path_, "line " + std::to_string(line) + ": " + reason);
    }

    // One `#KEY values` line (without the '#'); true when it closes the header.
    bool header_line(std::string_view rest, std::size_t at, Header& h) const {
        const std::string key(detail::next_token(rest));
        auto once = [&](bool& seen) {
            if (seen) throw fail(at, "repeated #" + key);
            seen = true;
        };
        auto word = [&](std::string& out) {
            out = std::string(detail::next_token(rest));
            if (out.empty()) throw fail(at, "#" + key + " needs a value");
            if (!detail::next_token(rest).empty()) throw fail(at, "#" + key + " takes one value");
        };
        if (key == "ALTA") {
            const std::string_view a = detail::next_token(rest), b = detail::next_token(rest);
            return (a == "END" && b == "HEADER") || (a == "HEADER" && b == "END");
        }
        if (key == "DIM") {
            once(h.has_dim);
            const std::string_view a = detail::next_token(rest), b = detail::next_token(rest);
            if (!detail::parse_count(a, kMaxDim, h.dim_in) || !detail::parse_count(b, kMaxDim, h.dim_out) ||
                h.dim_in == 0 || h.dim_out == 0 || !detail::next_token(rest).empty())
                throw fail(at, "#DIM needs two integers 1.." + std::to_string(kMaxDim) + " (input and output dimensions)");
        } else if (key == "PARAM_IN") {
            once(h.has_param_in);
            word(h.param_in);
        } else if (key == "PARAM_OUT") {
            once(h.has_param_out);
            word(h.param_out);
        } else if (key == "FORMAT") {
            once(h.has_format);
            word(h.format);
        } else if (key == "VS") {
            once(h.has_vs);
            const std::string_view v = detail::next_token(rest);
            if (!detail::parse_count(v, 2, h.vs) || !detail::next_token(rest).empty())
                throw fail(at, "#VS needs one of 0, 1, 2 (confidence columns per value), found " + detail::quote(v));
        }
        return false;
    }

    // Checks a complete header; the first error in the order a reader of the file would meet them.
    void finish(Header& h) const {
        if (h.format != "text") throw UnsupportedError(path_, "ALTA #FORMAT " + detail::quote(h.format) + ": only text files are read");
        if (!h.has_dim) throw FormatError(path_, "no #DIM line before the data (not an ALTA file?)");
        if (!h.has_param_in) throw FormatError(path_, "no #PARAM_IN line: the input parameterisation is needed");
        for (const ParamInfo& p : kParams)
            if (p.name == h.param_in) h.param = &p;
        if (!h.param)
            throw UnsupportedError(path_, "ALTA input parameterisation " + detail::quote(h.param_in) +
                                              " is not supported (supported: " + supported_names(kParams) + ")");
        if (h.dim_in != h.param->dim)
            throw FormatError(path_, "#DIM " + std::to_string(h.dim_in) + " " + std::to_string(h.dim_out) + " but " +
                                         h.param_in + " has " + std::to_string(h.param->dim) + " coordinates");
        for (const OutputInfo& o : kOutputs)
            if (o.name == h.param_out) h.output = &o;
        if (!h.output)
            throw UnsupportedError(path_, "ALTA output " + detail::quote(h.param_out) + " is not supported (supported: " +
                                              supported_names(kOutputs) + ")");
        if (!((h.dim_out == 1 && h.output->one) || (h.dim_out == 3 && h.output->three)))
            throw UnsupportedError(path_, "ALTA data with " + std::to_string(h.dim_out) + " output values per row in " +
                                              h.param_out + ": " +
                                              (h.output->one ? "one (monochrome) or three (RGB) are read"
                                                             : "three (R, G, B) are read"));
    }

    void parse_row(std::string_view line, std::size_t at, const Header& h, std::vector<double>& row) const {
        // ALTA's confidence columns (#VS) follow all the values and belong to the first.
        const std::size_t want = h.dim_in + h.dim_out + h.vs;
        row.clear();
        for (std::string_view token = detail::next_token(line); !token.empty(); token = detail::next_token(line)) {
            if (row.size() == want) throw fail(at, "more than the " + std::to_string(want) + " numbers of a row");
            double v = 0;
            if (!detail::parse_double(token, v)) throw fail(at, "expected a number, found " + detail::quote(token));
            row.push_back(v);
        }
        if (row.size() != want)
            throw fail(at, "a row needs " + std::to_string(want) + " numbers (" + std::to_string(h.dim_in) +
                               " coordinates, " + (h.dim_out == 1 ? std::string("the value") : "the 3 values") +
                               (h.vs ? ", " + std::to_string(h.vs) + " confidence" : "") + "), found " +
                               std::to_string(row.size()));
        for (std::size_t k = 0; k < h.dim_in; ++k)
            if (!std::isfinite(row[k])) throw fail(at, "coordinate " + std::to_string(k + 1) + " is not finite");
    }

    // {wi, wo} of a row's coordinates.
    std::pair<Vec3, Vec3> directions(const std::vector<double>& x, std::size_t at, const Header& h) const {
        auto polar = [&](double theta, const char* name) {
            if (theta < 0.0 || theta > std::numbers::pi)
                throw fail(at, std::string(name) + " = " + std::to_string(theta) + " outside [0, pi]");
            return theta;
        };
        if (h.param->param == Param::Cartesian) {
            // [V, L], as ALTA packs them: each a direction, normalised here (any finite non-zero vector).
            const auto unit = [&](std::size_t k, const char* name) {
                const Vec3 v{x[k], x[k + 1], x[k + 2]};
                const double n = length(v);
                if (!(n > 0.0) || !std::isfinite(n)) throw fail(at, std::string(name) + " is not a non-zero vector");
                return (1.0 / n) * v;
            };
            return {unit(3, "the light vector L"), unit(0, "the view vector V")};
        }
        if (h.param->param == Param::SphericalTlPlTvPv)
            return {spherical_direction(polar(x[0], "theta_l"), x[1]), spherical_direction(polar(x[2], "theta_v"), x[3])};
        if (h.param->param == Param::TlTvProjDphi) {
            const double theta_l = polar(x[0], "theta_l");
            const double theta_v = polar(std::hypot(x[1], x[2]), "theta_v (the length of the projected view)");
            const Vec3 wi{std::sin(theta_l), 0.0, std::cos(theta_l)};
            const double s = theta_v > 0.0 ? std::sin(theta_v) / theta_v : 0.0;
            return {wi, Vec3{s * x[1], s * x[2], std::cos(theta_v)}};
        }
        const bool full = h.param->param == Param::RusinThPhTdPd;
        const double theta_h = polar(x[0], "theta_h");
        const double phi_h = full ? x[1] : 0.0;
        const double theta_d = polar(x[full ? 2 : 1], "theta_d");
        const double phi_d = h.param->param == Param::RusinThTd ? std::numbers::pi / 2 : x[h.dim_in - 1];
        const auto [v, l] = rusinkiewicz(theta_h, phi_h, theta_d, phi_d);
        return {l, v};
    }

    const std::string& path_;
    std::string_view text_;
};

}  // namespace

ReadResult read(const std::string& path) {
    const std::string text = detail::read_text_file(path, kMaxFileBytes);
    Scanner scanner(path, text);

    ReadResult result;
    const Header header = scanner.scan([&](std::size_t line, const Vec3&, const Vec3&, const Rgb&) {
        if (++result.rows > kMaxRows)
            throw FormatError(path, "line " + std::to_string(line) + ": more than " + std::to_string(kMaxRows) + " rows");
    });
    if (result.rows == 0) throw FormatError(path, "no data rows after the header");
    result.param_in = header.param_in;
    result.param_out = header.param_out;

    MeasurementSet& set = result.set;
    set.channels = header.dim_out == 3 ? 3 : 1;
    set.source = path;
    set.samples.reserve(result.rows);
    ValidityCounts& counts = result.counts;
    scanner.scan([&](std::size_t, const Vec3& wi, const Vec3& wo, const Rgb& f) {
        bool nan = false, inf = false, negative = false;
        for (double c : f) nan |= std::isnan(c), inf |= std::isinf(c), negative |= c < 0.0;
        if (!detail::above_horizon(wi) || !detail::above_horizon(wo)) {
            ++counts.below_horizon;
            return;
        }
        // As for tables: a row counts in every class one of its values falls in.
        counts.nan += nan;
        counts.inf += inf;
        if (nan || inf) return;
        ++(negative ? counts.negative : counts.valid);
        set.samples.push_back({wi, wo, f});
    });
    if (set.samples.empty())
        throw FormatError(path, "no usable row: all " + std::to_string(result.rows) +
                                    " are below the horizon or not finite");
    return result;
}

}  // namespace brdfz::alta
