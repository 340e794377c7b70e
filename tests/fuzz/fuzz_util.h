// Shared by the libFuzzer harnesses: readers take paths, so each input is written to one temporary
// file per process (on tmpfs when there is one), and a loaded BRDF is evaluated at a few fixed
// direction pairs so that evaluation of hostile data is exercised too.
#pragma once

#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "brdfz/brdf.h"

namespace brdfz::fuzz {

// Writes the input to this process's file with the given extension and returns its path.
inline const std::string& input_file(const std::uint8_t* data, std::size_t size, const char* ext) {
    static const std::string path = [&] {
        const char* dir = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        return std::string(dir) + "/brdfz-fuzz-" + std::to_string(getpid()) + ext;
    }();
    std::FILE* f = std::fopen(path.c_str(), "wb");
    if (!f || std::fwrite(data, 1, size, f) != size || std::fclose(f) != 0) std::abort();
    return path;
}

// Touches eval (and, when asked, sampling) over the hemisphere; any result is fine, UB or a crash is
// not. Tables are not sampled here: building their sampler costs far more than reading them, and
// its input is any table, not the file.
inline void exercise(const Brdf& brdf, bool sample) {
    const Vec3 dirs[] = {{0, 0, 1}, {0.6, 0, 0.8}, {-0.3, 0.4, 0.866}, {0.99, 0.1, 0.0999}, {0, -0.999, 0.0447}};
    double sink = 0;
    for (const Vec3& a : dirs)
        for (const Vec3& b : dirs) {
            const Rgb f = brdf.eval(a, normalize(b));
            sink += f[0] + f[1] + f[2];
            if (sample) sink += brdf.sample(normalize(b), 0.3, 0.7).pdf + brdf.pdf(normalize(a), normalize(b));
        }
    volatile double keep = sink;
    (void)keep;
}

}  // namespace brdfz::fuzz
