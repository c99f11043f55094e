#pragma once
/// @file
/// @brief Where the hazard reach meets the ground: the footprint of the reach on the range, at
/// eye height over the terrain (or over the ellipsoid at the site's height where there is no
/// terrain), hidden where the ground stands between it and the lit centre (docs/terrain.md).

#include <memory>
#include <vector>

#include "export/exr_map.h"
#include "geo/site.h"
#include "geo/terrain.h"
#include "observers/far_field.h"
#include "observers/point_set.h"
#include "observers/reach.h"
#include "pipeline/input/scene.h"

namespace glint {

/// @brief The footprint on a square grid about the lit centre, seen from above.
struct ReachFootprint {
  PlaneGrid grid;  ///< horizontal, u = +x, v = +y of the site's frame
  /// Per threshold (HazardSpec::thresholdsW_m2(): the naked eye, aided, each level): 1 where the
  /// reach covers the observer at some
  /// corner or the centre of the pixel and the ground does not hide it from the lit centre, and
  /// within the lit ball (√3 × the reach's first layer), which the reach does not classify.
  std::vector<std::vector<unsigned char>> inside;
  std::vector<float> ground_z_m;  ///< the observers' local height (ground + eye height)
  std::vector<double> area_m2;    ///< per threshold: pixels inside × pixel²
  std::size_t hidden_pixels = 0;  ///< within the reach but hidden by the ground (naked eye)
  /// The same at each flight altitude of the spec (FootprintSpec::flight_altitudes_m), in order.
  struct Altitude {
    double altitude_m = 0.0;
    std::vector<std::vector<unsigned char>> inside;  ///< per threshold
    std::vector<double> area_m2;                     ///< per threshold
    std::size_t hidden_pixels = 0;
  };
  std::vector<Altitude> altitudes;
};

/// @brief The footprint of @p near and @p far (thresholds as the lattice's) on the ground of
/// @p site, over @p terrain where there is one.
/// @p counter, where given, counts the rows done: the footprint's rows at eye height and at
/// each altitude (footprintRows()).
/// @throw std::invalid_argument where the terrain does not reach a pixel.
ReachFootprint reachFootprint(const NearReach& near, const FarField& far, double extinction_per_m,
                              const SiteFrame& site, const Terrain* terrain,
                              const FootprintSpec& spec, WorkCounter* counter = nullptr);

/// @brief The rows reachFootprint() covers for @p spec: a side's pixels at eye height and at
/// each flight altitude.
std::size_t footprintRows(const FootprintSpec& spec);

}  // namespace glint
