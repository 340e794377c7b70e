// Analytic model files (.json): a model string and its named parameters, documented in
// docs/model-json.md. The stand-in output of `brdfz fit` until the .brdfz container stores models.
#pragma once

#include <string>
#include <utility>
#include <variant>
#include <vector>

#include "brdfz/repr/analytic/model.h"

namespace brdfz::model_json {

inline constexpr const char* kFormatName = "brdfz-analytic";
inline constexpr int kVersion = 1;
inline constexpr std::size_t kMaxFileBytes = 1 << 20;  // far above any model; checked before reading

// Informational "provenance" members (where the model came from, how well it fits): name -> text or number.
using Provenance = std::vector<std::pair<std::string, std::variant<std::string, double>>>;

// Reads and validates the whole file: FormatError naming the file for bad JSON, a wrong format or
// version, an unknown model, a missing, unknown, duplicated, non-numeric or out-of-bounds parameter;
// IoError when it cannot be read.
AnalyticBrdf read(const std::string& path);

// Writes atomically (formats/detail/atomic_file.h); parameters with 17 significant digits, so reading
// gives back the same doubles.
void write(const std::string& path, const AnalyticBrdf& model, const Provenance& provenance = {});

}  // namespace brdfz::model_json
