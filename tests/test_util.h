// Helpers shared by the C++ tests: temporary folders and the real-data locations.
#pragma once

#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

namespace brdfz::test {

// A fresh folder under the system temp dir, removed with its contents on destruction.
struct TempDir {
    std::filesystem::path path;
    TempDir() {
        std::random_device rd;
        path = std::filesystem::temp_directory_path() / ("brdfz-test-" + std::to_string(rd()) + std::to_string(rd()));
        std::filesystem::create_directories(path);
    }
    ~TempDir() {
        std::error_code ec;
        std::filesystem::remove_all(path, ec);
    }
    TempDir(const TempDir&) = delete;
    TempDir& operator=(const TempDir&) = delete;
};

// A shared RGL-EPFL file by material name (it may be missing: callers skip with a message).
inline std::filesystem::path rgl_file(const char* name) {
    return std::filesystem::path(BRDFZ_SHARED_DIR) / "data" / "rgl" / (std::string(name) + "_rgb.bsdf");
}

// MERL tables generated from ../shared by the ctest fixture (env BRDFZ_MERL_DIR); empty if none.
inline std::vector<std::filesystem::path> merl_tables() {
    std::vector<std::filesystem::path> files;
    const char* dir = std::getenv("BRDFZ_MERL_DIR");
    std::error_code ec;
    if (!dir || !std::filesystem::is_directory(dir, ec)) return files;
    for (const auto& e : std::filesystem::directory_iterator(dir))
        if (e.path().extension() == ".binary") files.push_back(e.path());
    std::sort(files.begin(), files.end());
    return files;
}

}  // namespace brdfz::test
