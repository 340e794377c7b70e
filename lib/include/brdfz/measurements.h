// Irregular measurements: BRDF values at scattered direction pairs. Cornell and ALTA files read into
// this, fitting consumes it, and metrics can be taken at its points. Directions follow brdf.h
// (unit vectors, normal +z, pointing away from the surface); f is f_r in 1/sr, no cosine.
#pragma once

#include <string>
#include <vector>

#include "brdfz/brdf.h"

namespace brdfz {

struct Measurement {
    Vec3 wi, wo;
    Rgb f;
};

struct MeasurementSet {
    std::vector<Measurement> samples;
    int channels = 3;    // 1: monochrome source, its value repeated in all three channels
    std::string source;  // where the samples came from, for reports
};

}  // namespace brdfz
