#pragma once
/// @file
/// @brief `glint fit`: closed forms (lobes, ABg, Lambert) fitted to a measured BRDF table.

#include <ostream>
#include <string>

#include "facets/material_fit.h"

namespace glint {

/// @brief The arguments of `glint fit`.
struct FitArgs {
  std::string table_path;  ///< the table's CSV (docs/scene.md, "Measured tables")
  MaterialFitModel model;
};

/// @brief Fits the model to the table and writes, to @p out, a JSON object: `material` (the
/// scene keys of the fitted material, ready for a scene's `materials`) and `fit` (the nodes
/// fitted, the RMS error of ln f_r, the largest relative error where the table holds at least
/// 1 % of its peak, the energy a scene checks, and the table's own largest hemispherical
/// reflectance). A fit whose energy is above 1 is written, with a warning on @p err.
/// @throw InputError on a table that cannot be read or a model out of range.
void runFit(const FitArgs& args, std::ostream& out, std::ostream& err);

}  // namespace glint
