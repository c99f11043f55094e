#pragma once
/// @file
/// @brief How an adaptive observer field differs from its uniform dense twin on the same
/// lattice: the figures the tests assert and the benchmark reports.

#include <array>
#include <cstdint>

#include "observers/field.h"

namespace glint {

/// @brief The adaptive field against the dense field, point by point over the lattice.
struct FieldComparison {
  double peak_w_m2 = 0.0;       ///< largest dense irradiance
  double max_error_w_m2 = 0.0;  ///< max |adaptive − dense| over the points dense evaluated
  Vec3 max_error_at_m{0.0};
  double rms_error_w_m2 = 0.0;
  /// What the field's accuracy promises: tolerance × peak + floor.
  double allowed_error_w_m2 = 0.0;
  /// Points where dense exceeds 10 × floor but the adaptive field proved them below it.
  std::int64_t bright_skipped = 0;
  /// Thresholds as shares of the peak, and the volume (m³) above each in either field.
  std::array<double, 3> threshold_shares{0.01, 0.1, 0.5};
  std::array<double, 3> adaptive_volume_m3{};
  std::array<double, 3> dense_volume_m3{};
  /// A level of irradiance given to compareFields (the MPE: then these are the nominal hazard
  /// zone's volumes), 0 when none was, and the volume (m³) above it in either field.
  double level_w_m2 = 0.0;
  double adaptive_level_volume_m3 = 0.0;
  double dense_level_volume_m3 = 0.0;

  /// @brief adaptive / dense volume above threshold @p t (1 where both are empty).
  [[nodiscard]] double volumeRatio(std::size_t t) const;
  /// @brief adaptive / dense volume above level_w_m2 (1 where both are empty).
  [[nodiscard]] double levelVolumeRatio() const;
  /// @brief The acceptance of the field against dense: error within allowed, every volume
  /// ratio within 1 %, no bright point skipped.
  [[nodiscard]] bool withinAccuracy() const;
};

/// @brief Compares @p adaptive with @p dense, computed over the same FieldSpec, and their
/// volumes above @p level_w_m2 where it is > 0.
/// @throws std::invalid_argument when their lattices differ.
FieldComparison compareFields(const ObserverField& adaptive, const ObserverField& dense,
                              double level_w_m2 = 0.0);

}  // namespace glint
