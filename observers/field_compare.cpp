#include "observers/field_compare.h"

#include <cmath>
#include <stdexcept>

namespace glint {

double FieldComparison::volumeRatio(std::size_t t) const {
  if (dense_volume_m3[t] == 0.0) return adaptive_volume_m3[t] == 0.0 ? 1.0 : 0.0;
  return adaptive_volume_m3[t] / dense_volume_m3[t];
}

double FieldComparison::levelVolumeRatio() const {
  if (dense_level_volume_m3 == 0.0) return adaptive_level_volume_m3 == 0.0 ? 1.0 : 0.0;
  return adaptive_level_volume_m3 / dense_level_volume_m3;
}

bool FieldComparison::withinAccuracy() const {
  if (!(max_error_w_m2 <= allowed_error_w_m2) || bright_skipped != 0) return false;
  for (std::size_t t = 0; t < threshold_shares.size(); ++t) {
    if (!(std::abs(volumeRatio(t) - 1.0) <= 0.01)) return false;
  }
  return true;
}

FieldComparison compareFields(const ObserverField& adaptive, const ObserverField& dense,
                              double level_w_m2) {
  const FieldSpec& spec = dense.spec();
  if (adaptive.spec().nodes() != spec.nodes() || adaptive.spec().voxel_m != spec.voxel_m ||
      adaptive.spec().min_m != spec.min_m) {
    throw std::invalid_argument("compareFields: the two fields have different lattices");
  }
  FieldComparison c;
  c.peak_w_m2 = dense.stats().peak_w_m2;
  c.allowed_error_w_m2 = spec.tolerance * c.peak_w_m2 + spec.floor_w_m2;
  const auto n = spec.nodes();
  double sum_squares = 0.0;
  std::int64_t count = 0;
  for (int i = 0; i < n[0]; ++i)
    for (int j = 0; j < n[1]; ++j)
      for (int k = 0; k < n[2]; ++k) {
        if (!integratedHere(dense.status(i, j, k))) continue;
        const double e = dense.irradiance(i, j, k);
        const double error = std::abs(adaptive.irradiance(i, j, k) - e);
        sum_squares += error * error;
        ++count;
        if (error > c.max_error_w_m2) {
          c.max_error_w_m2 = error;
          c.max_error_at_m = spec.position(i, j, k);
        }
        if (e > 10.0 * spec.floor_w_m2 && adaptive.status(i, j, k) == VoxelStatus::BelowFloor) {
          ++c.bright_skipped;
        }
      }
  c.rms_error_w_m2 = count > 0 ? std::sqrt(sum_squares / static_cast<double>(count)) : 0.0;
  for (std::size_t t = 0; t < c.threshold_shares.size(); ++t) {
    const double threshold = c.threshold_shares[t] * c.peak_w_m2;
    c.adaptive_volume_m3[t] = adaptive.volumeAbove(threshold);
    c.dense_volume_m3[t] = dense.volumeAbove(threshold);
  }
  if (level_w_m2 > 0.0) {
    c.level_w_m2 = level_w_m2;
    c.adaptive_level_volume_m3 = adaptive.volumeAbove(level_w_m2);
    c.dense_level_volume_m3 = dense.volumeAbove(level_w_m2);
  }
  return c;
}

}  // namespace glint
