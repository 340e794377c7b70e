// Writes a small material in the runtime layout (formats/SPEC.md §6: a constant 1x1x1 table and a
// one-cell compact sampler), opens it from the file and from memory, and checks eval, pdf and sample:
// exit 0 when the installed runtime reads the documented layout as a renderer would.
#include <brdfz/runtime/crc32c.h>
#include <brdfz/runtime/layout.h>
#include <brdfz/runtime/runtime.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <string>
#include <vector>

namespace L = brdfz::runtime::layout;

namespace {

struct Section {
    std::uint32_t tag;
    L::DType dtype;
    std::vector<unsigned char> bytes;
};

template <typename T>
Section section(std::uint32_t tag, L::DType dtype, std::vector<T> values) {
    Section s{tag, dtype, std::vector<unsigned char>(values.size() * sizeof(T))};
    std::memcpy(s.bytes.data(), values.data(), s.bytes.size());
    return s;
}

std::vector<unsigned char> layout(float value) {
    const std::vector<Section> sections = {
        section<std::int32_t>(L::kKind, L::DType::I32, {static_cast<std::int32_t>(L::Kind::Table)}),
        section<std::int32_t>(L::kGrid, L::DType::I32, {1, 1, 1, 1, L::kPhiDReciprocal, L::kLookupLinear}),
        section<double>(L::kWarp, L::DType::F64, {0.0}),
        section<float>(L::kValuesF32, L::DType::F32, {value, value, value}),
        section<std::int32_t>(L::kSamplerShape, L::DType::I32, {2, 1, 1}),
        section<double>(L::kSamplerParams, L::DType::F64, {0.0, 0.02}),
        section<float>(L::kSamplerEdges, L::DType::F32, {0.0f, 0.5f}),
        section<std::uint32_t>(L::kSamplerRows, L::DType::U32, {4294967295u, 4294967295u}),
        section<std::uint16_t>(L::kSamplerCols, L::DType::U16, {65535, 65535}),
        section<std::uint16_t>(L::kSamplerWeights, L::DType::F16, {0x3C00, 0x3C00, 0x3C00, 0x3C00}),
    };
    const auto align = [](std::size_t x) { return (x + L::kAlign - 1) / L::kAlign * L::kAlign; };
    std::size_t at = align(L::kHeaderBytes + sections.size() * L::kSectionBytes);
    std::vector<std::size_t> offsets;
    for (const Section& s : sections) offsets.push_back(at), at = align(at + s.bytes.size());
    std::vector<unsigned char> out(at, 0);
    const auto put = [&](std::size_t pos, auto v) { std::memcpy(out.data() + pos, &v, sizeof v); };
    std::memcpy(out.data(), L::kMagic, 8);
    put(8, L::kVersion);
    put(12, L::kHeaderBytes);
    put(16, static_cast<std::uint64_t>(out.size()));
    put(24, static_cast<std::uint32_t>(sections.size()));
    put(32, static_cast<std::uint32_t>(L::Kind::Table));
    put(36, std::uint32_t{1});
    for (std::size_t i = 0; i < sections.size(); ++i) {
        const std::size_t e = L::kHeaderBytes + i * L::kSectionBytes;
        put(e, sections[i].tag);
        put(e + 4, static_cast<std::uint32_t>(sections[i].dtype));
        put(e + 8, static_cast<std::uint64_t>(offsets[i]));
        put(e + 16, static_cast<std::uint64_t>(sections[i].bytes.size() / L::dtype_bytes(sections[i].dtype)));
        std::memcpy(out.data() + offsets[i], sections[i].bytes.data(), sections[i].bytes.size());
    }
    put(28, brdfz::runtime::crc32c(out.data() + L::kHeaderBytes, out.size() - L::kHeaderBytes));
    return out;
}

bool check(const brdfz::runtime::Material& m, float value) {
    const brdfz::runtime::Float3 wi{0.0f, 0.6f, 0.8f}, wo{0.0f, -0.6f, 0.8f}, below{0.0f, 0.0f, -1.0f};
    const brdfz::runtime::Rgb32 f = m.eval(wi, wo);
    const brdfz::runtime::Sample32 s = m.sample(wo, 0.3f, 0.7f);
    std::printf("f %g, sample pdf %g, weight %g\n", f.g, s.pdf, s.weight.g);
    return f.g == value && m.eval(below, wo).g == 0.0f && s.pdf > 0.0f && std::fabs(m.pdf(wo, s.wi) - s.pdf) < 1e-4f * s.pdf &&
           std::fabs(s.weight.g - value * s.wi.z / s.pdf) < 1e-4f * s.weight.g;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) return 2;
    const float value = 0.25f;
    const std::vector<unsigned char> bytes = layout(value);
    const std::string path = std::string(argv[1]) + "/constant.brdfzrt";
    std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
    std::string error;
    const brdfz::runtime::Material file = brdfz::runtime::Material::open(path, &error);
    if (!file) return std::printf("%s\n", error.c_str()), 1;
    const brdfz::runtime::Material memory = brdfz::runtime::Material::from_memory(bytes.data(), bytes.size(), false, &error);
    if (!memory) return std::printf("%s\n", error.c_str()), 1;
    return check(file, value) && check(memory, value) ? 0 : 1;
}
