#pragma once
/// @file
/// @brief The result table of `glint points` (PHYSICS.md, "Points file and output").

#include <ostream>
#include <span>

#include "facets/integrator.h"

namespace glint {

/// @brief Writes the header `x,y,z,irradiance_w_m2,error_estimate_w_m2,evaluations,converged`
/// and one row per observer, in order. Numbers are written in their shortest exact decimal form,
/// so x, y, z read back as the very values that came in.
/// @throw OutputError if any value is not finite (a defect upstream; nothing is written then).
void writePointsCsv(std::ostream& out, std::span<const Vec3> points_m,
                    std::span<const ObserverResult> results);

}  // namespace glint
