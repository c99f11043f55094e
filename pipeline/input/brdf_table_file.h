#pragma once
/// @file
/// @brief A measured BRDF table from its CSV file (docs/scene.md, "Measured tables").

#include <cstdint>
#include <filesystem>
#include <memory>

#include "facets/brdf_table.h"

namespace glint {

/// @brief The table in @p path: a header `theta_i_deg,theta_o_deg,delta_phi_deg,brdf_per_sr`,
/// then one row per node of a full rectilinear grid, in any order (blank lines and lines from
/// `#` on are skipped). Δφ is measured from the laser's azimuth: 180° holds the mirror direction.
/// @throw InputError naming the file, the line and what is wrong (a row that is not four
/// finite numbers, a node out of range or given twice, a node of the grid missing, two nodes
/// closer than 0.05°) or what it would cost against the budget.
/// With @p memory_budget_bytes (0: none), what reading and holding it will take is counted
/// before each step (its text, its rows, its grid) with what the process holds already, and a
/// table that would pass the budget is refused; so is a file that is not a regular one.
std::shared_ptr<const BrdfTable> readBrdfTable(const std::filesystem::path& path,
                                               std::uint64_t memory_budget_bytes = 0);

}  // namespace glint
