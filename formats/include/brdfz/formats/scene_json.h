// Scene files (.json): which direction pairs a scene uses, for scene-driven error budgets
// (brdfz/scene.h). The schema is documented in docs/scene-json.md.
#pragma once

#include <string>

#include "brdfz/scene.h"

namespace brdfz::scene_json {

inline constexpr const char* kFormatName = "brdfz-scene";
inline constexpr int kVersion = 1;
inline constexpr std::size_t kMaxFileBytes = 16 << 20;  // explicit pair lists can be long

// Reads and validates the file's structure: FormatError naming the file for bad JSON, a wrong format
// or version, an unknown or mistyped member; IoError when it cannot be read. Values are checked by
// build_scene (ValueError naming the member).
SceneDescription read(const std::string& path);

// read() and build_scene(): the scene's samples, or read()'s errors, or build_scene's ValueError with
// the file's name before it.
Scene load(const std::string& path);

}  // namespace brdfz::scene_json
