// RGL .bsdf writer: tensors from any Brdf (rgl_writer.h) and the tensor_file serialisation
// (tensor_file.h describes the layout).
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <numbers>
#include <vector>

#include "brdfz/errors.h"
#include "brdfz/formats/rgl_writer.h"
#include "detail/atomic_file.h"
#include "detail/bytes.h"
#include "aniso.h"
#include "marginal2d.h"
#include "tensor_file.h"

namespace brdfz::rgl {
namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kUniformShare = 0.2;            // of D, spread uniformly over the hemisphere
constexpr double kCosineShare = 0.3;             // of the warp, spread cosine-weighted over wo
constexpr double kThetaMax = 89.0 * kPi / 180.0;  // last θi slice
constexpr double kMinCosine = 1e-4;              // floor on m·wi: every warp row has mass
constexpr double kLuminanceFloor = 1e-3;         // of a slice's mean, so every slice can be sampled

double theta_of_u(double u) { return u * u * (kPi / 2.0); }
double luminance(double r, double g, double b) { return 0.2126 * r + 0.7152 * g + 0.0722 * b; }
Vec3 in_plane(double theta) { return {std::sin(theta), 0.0, std::cos(theta)}; }

// The microfacet normal at unit coordinates u (φ relative to φi = 0).
Vec3 normal_at(double ux, double uy) {
    const double theta = theta_of_u(ux), phi = (2.0 * uy - 1.0) * kPi;
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// dωo/du_m, the solid angle of reflected directions per unit area of the warp's square, up to the
// constant 8π²: u_θ·sinθm·(m·wi), floored.
double jacobian(double ux, const Vec3& m, const Vec3& wi) {
    return ux * std::sin(theta_of_u(ux)) * std::max(dot(m, wi), kMinCosine);
}

// D at u_θ from an isotropic ndf row, interpolated linearly as the reader does.
double ndf_at(const std::vector<double>& d, double u) {
    const double x = std::clamp(u, 0.0, 1.0) * static_cast<double>(d.size() - 1);
    const std::size_t i = std::min(static_cast<std::size_t>(x), d.size() - 2);
    const double t = x - static_cast<double>(i);
    return d[i] * (1.0 - t) + d[i + 1] * t;
}

// Midpoint quadrature over u_θ ∈ [0, 1] of g(u, θ)·dθ, dθ = π·u du.
template <typename G>
double integrate_theta(const G& g) {
    constexpr int kSteps = 4096;
    double sum = 0.0;
    for (int k = 0; k < kSteps; ++k) {
        const double u = (k + 0.5) / kSteps;
        sum += g(u, theta_of_u(u)) * kPi * u;
    }
    return sum / kSteps;
}

// D(θ) ∝ Y(f(w, w))·cos²θ at the ndf columns (a microfacet BRDF's retro-reflection is F·D·G/(4cos²θ)),
// normalised to ∫ D cosθ dω = 1 and mixed with the uniform D = 1/π.
std::vector<double> derive_ndf(const Brdf& brdf, int n) {
    std::vector<double> d(n);
    for (int j = 0; j < n; ++j) {
        const double theta = theta_of_u(static_cast<double>(j) / (n - 1));
        const Vec3 w = in_plane(std::min(theta, kThetaMax));
        const Rgb f = brdf.eval(w, w);
        const double c = std::cos(theta), y = luminance(f[0], f[1], f[2]) * c * c;
        d[j] = std::isfinite(y) && y > 0.0 ? y : 0.0;
    }
    const double total =
        2.0 * kPi * integrate_theta([&](double u, double t) { return ndf_at(d, u) * std::cos(t) * std::sin(t); });
    for (double& v : d) v = total > 0.0 ? (1.0 - kUniformShare) * v / total + kUniformShare / kPi : 1.0 / kPi;
    return d;
}

// σ(θi) = ∫ D(m) max(0, m·wi) dωm; the azimuthal integral of max(0, a + b cosφ) is exact.
double projected_area(const std::vector<double>& d, double theta_i) {
    const double ci = std::cos(theta_i), si = std::sin(theta_i);
    return integrate_theta([&](double u, double t) {
        const double a = std::cos(t) * ci, b = std::sin(t) * si;
        double azimuthal;  // ∫_0^{2π} max(0, a + b cosφ) dφ
        if (a >= b) {
            azimuthal = 2.0 * kPi * a;
        } else if (a <= -b) {
            azimuthal = 0.0;
        } else {
            const double phi0 = std::acos(-a / b);
            azimuthal = 2.0 * (a * phi0 + b * std::sin(phi0));
        }
        return ndf_at(d, u) * azimuthal * std::sin(t);
    });
}

// An isotropic table: 2 identical rows (φ = -π and π) of columns along u_θ.
Grids isotropic(const std::vector<double>& row) {
    Grids g;
    g.rows = 2;
    g.cols = row.size();
    for (int r = 0; r < 2; ++r)
        for (double v : row) g.values.push_back(static_cast<float>(v));
    return g;
}

Grids square(std::size_t slices, int n) {
    Grids g;
    g.slices = slices;
    g.rows = g.cols = static_cast<std::size_t>(n);
    g.values.assign(slices * g.rows * g.cols, 0.0f);
    return g;
}

// Y of each rgb grid point, clamped at 0, plus the floor: for files whose warps follow their
// microfacet distribution (RGL's own), whose rgb values are then already per unit of the warp.
Grids luminance_of(const Grids& rgb) {
    Grids lum;
    lum.slices = rgb.slices / 3;
    lum.rows = rgb.rows;
    lum.cols = rgb.cols;
    const std::size_t plane = rgb.rows * rgb.cols;
    lum.values.resize(lum.slices * plane);
    for (std::size_t s = 0; s < lum.slices; ++s) {
        const float* c = rgb.values.data() + 3 * s * plane;
        float* y = lum.values.data() + s * plane;
        double mean = 0.0;
        for (std::size_t k = 0; k < plane; ++k) {
            y[k] = static_cast<float>(std::max(0.0, luminance(c[k], c[plane + k], c[2 * plane + k])));
            mean += y[k] / static_cast<double>(plane);
        }
        const double floor = mean > 0.0 ? kLuminanceFloor * mean : 1.0;
        for (std::size_t k = 0; k < plane; ++k) y[k] += static_cast<float>(floor);
    }
    return lum;
}

// ---- tensor_file serialisation ----

struct OutField {
    std::string name;
    detail::DType dtype;
    std::vector<std::uint64_t> shape;
    const void* data;
    std::uint64_t bytes;
};

template <typename T>
void put(std::vector<unsigned char>& b, T v) {
    v = brdfz::detail::to_little_endian(v);
    const auto* p = reinterpret_cast<const unsigned char*>(&v);
    b.insert(b.end(), p, p + sizeof v);
}

void write_tensor_file(const std::string& path, const std::vector<OutField>& fields) {
    static_assert(std::endian::native == std::endian::little, "float data are written in host order");
    std::vector<unsigned char> header;
    const char magic[] = "tensor_file";
    header.insert(header.end(), magic, magic + sizeof magic);  // with its NUL
    header.push_back(1);
    header.push_back(0);
    put<std::uint32_t>(header, static_cast<std::uint32_t>(fields.size()));
    std::uint64_t size = header.size();
    for (const OutField& f : fields) size += 2 + f.name.size() + 2 + 1 + 8 + 8 * f.shape.size();
    // Field data follow the table, each at an 8-byte aligned offset.
    std::vector<std::uint64_t> offsets;
    for (const OutField& f : fields) {
        size = (size + 7) / 8 * 8;
        offsets.push_back(size);
        size += f.bytes;
    }
    for (std::size_t k = 0; k < fields.size(); ++k) {
        const OutField& f = fields[k];
        put<std::uint16_t>(header, static_cast<std::uint16_t>(f.name.size()));
        header.insert(header.end(), f.name.begin(), f.name.end());
        put<std::uint16_t>(header, static_cast<std::uint16_t>(f.shape.size()));
        header.push_back(static_cast<unsigned char>(f.dtype));
        put<std::uint64_t>(header, offsets[k]);
        for (std::uint64_t d : f.shape) put<std::uint64_t>(header, d);
    }
    brdfz::detail::AtomicFile file(path);
    file.write(header.data(), header.size());
    std::uint64_t pos = header.size();
    const unsigned char zeros[8] = {};
    for (std::size_t k = 0; k < fields.size(); ++k) {
        file.write(zeros, offsets[k] - pos);
        file.write(fields[k].data, fields[k].bytes);
        pos = offsets[k] + fields[k].bytes;
    }
    file.commit();
}

// ---- anisotropic tables (nφ >= 3 φi slices over [-π, π], absolute azimuths; aniso.h) ----

Vec3 direction(double theta, double phi) {
    return {std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi), std::cos(theta)};
}

// Midpoint quadrature nodes over the square (u_θ across, u_φ down) with their solid angle, for the
// ndf's normalisation and sigma.
struct Node {
    double ux, uy, d_omega;
    Vec3 m;
};
std::vector<Node> nodes(int n) {
    std::vector<Node> out;
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const double ux = (i + 0.5) / n, uy = (j + 0.5) / n, theta = theta_of_u(ux);
            // dω = sinθ dθ dφ, dθ = π u_θ du_θ, dφ = 2π du_φ
            out.push_back({ux, uy, std::sin(theta) * kPi * ux * 2.0 * kPi / (static_cast<double>(n) * n),
                           normal_at(ux, uy)});
        }
    return out;
}

// D(m) ∝ Y(f(m, m))·cos²θm over the ndf grid (u_θm across, absolute u_φm down), normalised to
// ∫ D cosθ dω = 1 and mixed with the uniform D = 1/π; sigma(wi) = ∫ D(m) max(0, m·wi) dωm over the
// same grid; both read bilinearly as the readers do.
void derive_ndf_sigma(const Brdf& brdf, int n, Tensors& t) {
    t.ndf.rows = t.ndf.cols = t.sigma.rows = t.sigma.cols = static_cast<std::size_t>(n);
    std::vector<Vec3> w(static_cast<std::size_t>(n) * n);
    for (std::size_t c = 0; c < w.size(); ++c) {
        const Vec3 m = normal_at(static_cast<double>(c % n) / (n - 1), static_cast<double>(c / n) / (n - 1));
        w[c] = direction(std::min(elevation(m), kThetaMax), std::atan2(m.y, m.x));
    }
    std::vector<Rgb> f(w.size());
    brdf.eval(w, w, f);
    std::vector<double> d(w.size());
    for (std::size_t c = 0; c < w.size(); ++c) {
        const double cz = std::cos(theta_of_u(static_cast<double>(c % n) / (n - 1)));
        const double y = luminance(f[c][0], f[c][1], f[c][2]) * cz * cz;
        d[c] = std::isfinite(y) && y > 0.0 ? y : 0.0;
    }
    const auto at = [&](double ux, double uy) {
        const double x = ux * (n - 1), y = uy * (n - 1);
        const int i = std::min(static_cast<int>(x), n - 2), j = std::min(static_cast<int>(y), n - 2);
        const double fx = x - i, fy = y - j;
        const auto v = [&](int a, int b) { return d[static_cast<std::size_t>(b) * n + a]; };
        return (v(i, j) * (1 - fx) + v(i + 1, j) * fx) * (1 - fy) + (v(i, j + 1) * (1 - fx) + v(i + 1, j + 1) * fx) * fy;
    };
    const std::vector<Node> q = nodes(std::max(n, 64));
    double total = 0.0;
    for (const Node& node : q) total += at(node.ux, node.uy) * node.m.z * node.d_omega;
    for (double& v : d) v = total > 0.0 ? (1.0 - kUniformShare) * v / total + kUniformShare / kPi : 1.0 / kPi;
    std::vector<double> dq(q.size());
    for (std::size_t k = 0; k < q.size(); ++k) dq[k] = at(q[k].ux, q[k].uy) * q[k].d_omega;
    t.ndf.values.assign(d.begin(), d.end());
    t.sigma.values.resize(d.size());
    for (std::size_t c = 0; c < d.size(); ++c) {
        const Vec3 wi = direction(theta_of_u(static_cast<double>(c % n) / (n - 1)),
                                  (2.0 * static_cast<double>(c / n) / (n - 1) - 1.0) * kPi);
        double sigma = 0.0;
        for (std::size_t k = 0; k < q.size(); ++k) sigma += dq[k] * std::max(dot(q[k].m, wi), 0.0);
        t.sigma.values[c] = static_cast<float>(sigma);
    }
}

// The warp of one slice, incident direction wi, as nv × nv samples over (u_θm across, u_φm down): a
// mixture of the BRDF's own lobe there, Y(f)·cosθo·dωo/du_m, which puts the rgb samples where the
// reflected energy is, and of cosθo·dωo/du_m (kCosineShare), which keeps every reflected direction sampled.
void vndf_slice(const Brdf& brdf, const Vec3& wi, int nv, float* out) {
    const std::size_t cells = static_cast<std::size_t>(nv) * nv;
    std::vector<Vec3> wis(cells, wi), wos(cells);
    std::vector<Rgb> f(cells);
    std::vector<double> cosine(cells);
    for (std::size_t c = 0; c < cells; ++c) {
        const double ux = static_cast<double>(c % nv) / (nv - 1), uy = static_cast<double>(c / nv) / (nv - 1);
        const Vec3 m = normal_at(ux, uy);
        wos[c] = 2.0 * dot(m, wi) * m - wi;
        cosine[c] = jacobian(ux, m, wi) * std::max(wos[c].z, 0.0);
    }
    brdf.eval(wis, wos, f);
    double lobe_total = 0.0, cosine_total = 0.0;
    for (std::size_t c = 0; c < cells; ++c) {
        const double y = luminance(f[c][0], f[c][1], f[c][2]) * cosine[c];
        f[c][0] = std::isfinite(y) && y > 0.0 ? y : 0.0;  // reused as the lobe's weight
        lobe_total += f[c][0];
        cosine_total += cosine[c];
    }
    const double share = lobe_total > 0.0 ? kCosineShare : 1.0;
    for (std::size_t c = 0; c < cells; ++c)
        out[c] = static_cast<float>((lobe_total > 0.0 ? (1.0 - share) * f[c][0] / lobe_total : 0.0) +
                                    share * cosine[c] / cosine_total);
}

// rgb and luminance of one slice (incident direction wi) at the warped points (ux, uy) of the grid,
// whose warp densities are u_pdf: rgb is f over the scale a reader of these tables applies (scale_of,
// a reader whose rgb values are all 1), luminance Y(f)·cosθo per unit of the square plus a floor.
void rgb_slice(const Brdf& brdf, const Brdf& scale_of, const Vec3& wi, const std::vector<double>& ux,
               const std::vector<double>& uy, const std::vector<double>& u_pdf, float* rgb, float* lum) {
    const std::size_t plane = ux.size();
    std::vector<Vec3> wis(plane, wi), wos(plane);
    std::vector<Rgb> f(plane), scale(plane);
    std::vector<double> per_unit(plane);
    for (std::size_t p = 0; p < plane; ++p) {
        const Vec3 m = normal_at(ux[p], uy[p]);
        wos[p] = 2.0 * dot(m, wi) * m - wi;
        per_unit[p] = u_pdf[p] > 0.0 ? jacobian(ux[p], m, wi) / u_pdf[p] : 0.0;
    }
    brdf.eval(wis, wos, f);
    scale_of.eval(wis, wos, scale);
    double mean = 0.0;
    for (std::size_t p = 0; p < plane; ++p) {
        for (int c = 0; c < 3; ++c) {
            const double v = scale[p][c] > 0.0 ? f[p][c] / scale[p][c] : 0.0;
            rgb[c * plane + p] = std::isfinite(v) ? static_cast<float>(v) : 0.0f;
        }
        const double y = luminance(f[p][0], f[p][1], f[p][2]) * std::max(wos[p].z, 0.0) * per_unit[p];
        lum[p] = std::isfinite(y) && y > 0.0 ? static_cast<float>(y) : 0.0f;
        mean += lum[p] / static_cast<double>(plane);
    }
    const double floor = mean > 0.0 ? kLuminanceFloor * mean : 1.0;  // nothing reflected: uniform
    for (std::size_t p = 0; p < plane; ++p) lum[p] += static_cast<float>(floor);
}

Tensors derive_anisotropic(const Brdf& brdf, const WriteOptions& options) {
    const int n = options.n_theta_i, np = options.n_phi_i, nv = options.vndf_resolution, nr = options.rgb_resolution;
    const std::size_t slices = static_cast<std::size_t>(np) * n;
    Tensors t;
    t.jacobian = true;
    derive_ndf_sigma(brdf, options.ndf_resolution, t);
    for (int p = 0; p < np; ++p) t.phi_i.push_back(static_cast<float>(kPi * (2.0 * p / (np - 1) - 1.0)));
    for (int k = 0; k < n; ++k) t.theta_i.push_back(static_cast<float>(kThetaMax * k / (n - 1)));
    // wi of slice s; at θi = 0 every φi slice sees the same direction (and so holds the same tables).
    const auto incident = [&](std::size_t s) {
        return direction(t.theta_i[s % n], s % n == 0 ? 0.0 : static_cast<double>(t.phi_i[s / n]));
    };

    // The warp per slice (vndf_slice).
    t.vndf = square(slices, nv);
    for (std::size_t s = 0; s < slices; ++s)
        vndf_slice(brdf, incident(s), nv, t.vndf.values.data() + s * static_cast<std::size_t>(nv) * nv);

    // rgb and luminance at each grid point of each slice, as derive()'s.
    Tensors ones = t;
    ones.rgb = square(3 * slices, nr);
    std::fill(ones.rgb.values.begin(), ones.rgb.values.end(), 1.0f);
    const RglBrdf scale_of(std::move(ones));
    const detail::SliceWarp warp("rgl: vndf", t.vndf.values, slices, t.vndf.rows, t.vndf.cols);
    t.rgb = square(3 * slices, nr);
    t.luminance = square(slices, nr);
    const std::size_t plane = static_cast<std::size_t>(nr) * nr;
    std::vector<double> ux(plane), uy(plane), u_pdf(plane);
    for (std::size_t s = 0; s < slices; ++s) {
        detail::Corners slice;
        slice.slice[0] = s;
        for (std::size_t p = 0; p < plane; ++p) {
            const detail::WarpPoint u = warp.sample(static_cast<double>(p % nr) / (nr - 1),
                                                    static_cast<double>(p / nr) / (nr - 1), slice);
            ux[p] = u.x, uy[p] = u.y, u_pdf[p] = u.pdf;
        }
        rgb_slice(brdf, scale_of, incident(s), ux, uy, u_pdf, t.rgb.values.data() + 3 * s * plane,
                  t.luminance.values.data() + s * plane);
    }
    return t;
}

OutField f32_field(const char* name, std::vector<std::uint64_t> shape, const std::vector<float>& v) {
    return {name, detail::DType::F32, std::move(shape), v.data(), v.size() * sizeof(float)};
}

}  // namespace

Tensors derive(const Brdf& brdf, const WriteOptions& options) {
    for (int n : {options.vndf_resolution, options.rgb_resolution, options.ndf_resolution, options.n_theta_i})
        if (n < 2 || n > 4096) throw ValueError("rgl::derive: resolutions must be in 2..4096");
    if (options.n_phi_i != 1 && (options.n_phi_i < 3 || options.n_phi_i > 4096))
        throw ValueError("rgl::derive: n_phi_i must be 1 (isotropic) or in 3..4096");
    if (options.n_phi_i > 1) return derive_anisotropic(brdf, options);
    const int n = options.n_theta_i, nv = options.vndf_resolution, nr = options.rgb_resolution;

    Tensors t;
    t.jacobian = true;
    const std::vector<double> d = derive_ndf(brdf, options.ndf_resolution);
    t.ndf = isotropic(d);
    std::vector<double> sigma(d.size());
    for (std::size_t j = 0; j < d.size(); ++j)
        sigma[j] = projected_area(d, theta_of_u(static_cast<double>(j) / static_cast<double>(d.size() - 1)));
    t.sigma = isotropic(sigma);
    for (int k = 0; k < n; ++k) t.theta_i.push_back(static_cast<float>(kThetaMax * k / (n - 1)));

    // The warp per slice (vndf_slice).
    t.vndf = square(static_cast<std::size_t>(n), nv);
    for (int k = 0; k < n; ++k)
        vndf_slice(brdf, in_plane(t.theta_i[k]), nv, t.vndf.values.data() + static_cast<std::size_t>(k) * nv * nv);

    // rgb at each grid point s of each slice: m = warp(s), wo = wi reflected about m, and the value
    // from which the reader (and Mitsuba) reproduce f(wi, wo) there: f over the scale they apply,
    // D(m)/(4σ(wi))/cosθo with D and σ as interpolated from the tables, taken from a reader of the
    // same tables whose rgb values are all 1. 0 below the horizon.
    // luminance: Y(f)·cosθo per unit of the square, Y·(dωo/du_m)/pdf(u_m), so that sampling by it and
    // the warp draws wo in proportion to Y(f)·cosθo (plus a floor).
    Tensors ones = t;
    ones.rgb = square(3 * static_cast<std::size_t>(n), nr);
    std::fill(ones.rgb.values.begin(), ones.rgb.values.end(), 1.0f);
    const RglBrdf scale_of(std::move(ones));
    const detail::Marginal2D warp("rgl: vndf", t.vndf.values, t.vndf.slices, t.vndf.rows, t.vndf.cols);
    t.rgb = square(3 * static_cast<std::size_t>(n), nr);
    t.luminance = square(static_cast<std::size_t>(n), nr);
    const std::size_t plane = static_cast<std::size_t>(nr) * nr;
    std::vector<double> ux(plane), uy(plane), u_pdf(plane);
    const detail::WarpTables warp_tables = warp.tables();
    for (int k = 0; k < n; ++k) {
        for (std::size_t p = 0; p < plane; ++p) {
            ux[p] = static_cast<double>(p % nr) / (nr - 1);
            uy[p] = static_cast<double>(p / nr) / (nr - 1);
        }
        detail::sample_warp(warp_tables, k, ux.data(), uy.data(), u_pdf.data(), plane);
        rgb_slice(brdf, scale_of, in_plane(t.theta_i[k]), ux, uy, u_pdf,
                  t.rgb.values.data() + 3 * static_cast<std::size_t>(k) * plane,
                  t.luminance.values.data() + static_cast<std::size_t>(k) * plane);
    }
    return t;
}

std::size_t write(const std::string& path, const Brdf& brdf, const WriteOptions& options) {
    const auto* source = dynamic_cast<const RglBrdf*>(&brdf);
    Tensors t = source ? source->tensors() : derive(brdf, options);
    if (t.luminance.values.empty()) t.luminance = luminance_of(t.rgb);

    const std::string description = options.description.empty() ? brdf.describe() : options.description;
    const std::vector<float> phi_i = t.phi_i.size() > 1 ? t.phi_i : std::vector<float>{0.0f};
    const std::uint8_t jacobian = t.jacobian ? 1 : 0;
    const std::uint64_t np = phi_i.size(), n = t.theta_i.size(), rows = t.rgb.rows, cols = t.rgb.cols;
    const std::vector<std::uint8_t> valid(rows * cols, 1);
    write_tensor_file(path, {
        {"description", detail::DType::U8, {description.size()}, description.data(), description.size()},
        f32_field("phi_i", {np}, phi_i),
        f32_field("theta_i", {n}, t.theta_i),
        f32_field("sigma", {t.sigma.rows, t.sigma.cols}, t.sigma.values),
        f32_field("ndf", {t.ndf.rows, t.ndf.cols}, t.ndf.values),
        f32_field("vndf", {np, n, t.vndf.rows, t.vndf.cols}, t.vndf.values),
        f32_field("luminance", {np, n, rows, cols}, t.luminance.values),
        f32_field("rgb", {np, n, 3, rows, cols}, t.rgb.values),
        {"jacobian", detail::DType::U8, {1}, &jacobian, 1},
        {"valid", detail::DType::U8, {rows * cols}, valid.data(), valid.size()},
    });
    return np * n * rows * cols;
}

}  // namespace brdfz::rgl
