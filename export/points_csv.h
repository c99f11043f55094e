#pragma once
/// @file
/// @brief The result table of `glint points` (docs/physics.md, "The points file and the output
/// table").

#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "facets/integrator.h"

namespace glint {

/// @brief A further column of the table: one value per observer.
struct CsvColumn {
  std::string name;
  std::vector<double> values;
  bool integer = false;  ///< written as a whole number (values exact in a double)
};

/// @brief Writes the header `x,y,z,irradiance_w_m2,error_estimate_w_m2,evaluations,converged`
/// followed by the names of @p extra, and one row per observer, in order. Numbers are written in
/// their shortest exact decimal form, so x, y, z read back as the very values that came in.
/// @throw OutputError if any value is not finite or a column's length differs (a defect
/// upstream; nothing is written then).
void writePointsCsv(std::ostream& out, std::span<const Vec3> points_m,
                    std::span<const ObserverResult> results, std::span<const CsvColumn> extra = {});

/// @brief Writes the header `x,y,z` followed by the names of @p columns, and one row per
/// point, as writePointsCsv() writes its numbers (an engagement's table: docs/engagement.md).
/// @throw OutputError as writePointsCsv().
void writeColumnsCsv(std::ostream& out, std::span<const Vec3> points_m,
                     std::span<const CsvColumn> columns);

}  // namespace glint
