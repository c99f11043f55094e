#include "pipeline/setup/reach_footprint.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <string>

namespace glint {

namespace {

double footprintPixelM(const FootprintSpec& spec) {
  return spec.pixel_m > 0.0 ? spec.pixel_m : 2.0 * spec.radius_m / 512.0;
}

int footprintSide(const FootprintSpec& spec) {
  return 2 * static_cast<int>(std::ceil(spec.radius_m / footprintPixelM(spec))) + 1;
}

}  // namespace

std::size_t footprintRows(const FootprintSpec& spec) {
  return static_cast<std::size_t>(footprintSide(spec)) * (1 + spec.flight_altitudes_m.size());
}

ReachFootprint reachFootprint(const NearReach& near, const FarField& far, double extinction_per_m,
                              const SiteFrame& site, const Terrain* terrain,
                              const FootprintSpec& spec, WorkCounter* counter) {
  const Vec3 c = near.spec.centre_m;
  const double pixel = footprintPixelM(spec);
  const int n = footprintSide(spec);
  ReachFootprint f;
  PlaneGrid& g = f.grid;
  g.width = g.height = n;
  g.pixel_m = pixel;
  g.u_axis = {1.0, 0.0, 0.0};
  g.v_axis = {0.0, 1.0, 0.0};
  g.origin_m = {c.x - (n / 2) * pixel, c.y - (n / 2) * pixel, 0.0};
  const std::size_t thresholds = near.spec.thresholds_w_m2.size();
  const auto count = static_cast<std::size_t>(n) * static_cast<std::size_t>(n);
  f.ground_z_m.resize(count);
  const double site_height = site.spec().height_m;
  // The reach's lattice starts on the faces of a small cube about the lit centre (reachStartM()):
  // nothing inside it is classified, so every point within its circumscribed ball counts.
  const double unclassified_m = std::sqrt(3.0) * reachStartM(near.spec);
  // The site's conversions are not shared between threads: each thread converts with its own.
  tbb::enumerable_thread_specific<std::unique_ptr<SiteFrame>> frames;
  const auto localSite = [&]() -> const SiteFrame& {
    std::unique_ptr<SiteFrame>& mine = frames.local();
    if (!mine) mine = std::make_unique<SiteFrame>(site.spec());
    return *mine;
  };
  // The ground under local (x, y): the terrain's, or the ellipsoid's surface at the site's height.
  const auto ground = [&](double x, double y) -> double {
    if (terrain != nullptr) {
      const std::optional<double> z = terrain->surfaceZ(x, y);
      if (!z) {
        throw std::invalid_argument("the terrain does not reach the footprint's point (" +
                                    std::to_string(x) + ", " + std::to_string(y) + ") m");
      }
      return *z;
    }
    const SiteFrame& frame = localSite();
    const Geodetic here = frame.toGeodetic({x, y, 0.0});
    return frame.fromGeodetic({here.latitude_deg, here.longitude_deg, site_height}).z;
  };
  // The ground under each pixel, found once for eye height and every altitude above it.
  std::vector<double> ground_m(count);
  tbb::parallel_for(0, n, [&](int j) {
    for (int i = 0; i < n; ++i) {
      ground_m[static_cast<std::size_t>(j) * static_cast<std::size_t>(n) +
               static_cast<std::size_t>(i)] =
          ground(g.origin_m.x + i * pixel, g.origin_m.y + j * pixel);
    }
  });
  // Which pixels the reach covers with pixel k's observer at height z(k, x, y), into @p inside
  // and @p area_m2 (per threshold), counting in @p hidden those the ground hides. Rows in
  // parallel, each counting its own pixels; the areas are the counts times the pixel's area,
  // the same on any number of threads.
  const auto cover = [&](const auto& height, std::vector<std::vector<unsigned char>>& inside,
                         std::vector<double>& area_m2, std::size_t& hidden) {
    inside.assign(thresholds, std::vector<unsigned char>(count, 0));
    struct RowCount {
      std::vector<std::size_t> inside;
      std::size_t hidden = 0;
    };
    std::vector<RowCount> rows(static_cast<std::size_t>(n));
    tbb::parallel_for(0, n, [&](int j) {
      RowCount& row = rows[static_cast<std::size_t>(j)];
      row.inside.assign(thresholds, 0);
      std::vector<char> reached(thresholds, 0);  // per threshold, for the pixel at hand
      for (int i = 0; i < n; ++i) {
        const double x = g.origin_m.x + i * pixel, y = g.origin_m.y + j * pixel;
        const std::size_t k =
            static_cast<std::size_t>(j) * static_cast<std::size_t>(n) + static_cast<std::size_t>(i);
        const double z = height(k, x, y);
        // The reach at the pixel's centre and corners: any of them inside puts the pixel in.
        std::fill(reached.begin(), reached.end(), 0);
        for (const auto& [dx, dy] :
             {std::pair{0.0, 0.0}, {-0.5, -0.5}, {0.5, -0.5}, {-0.5, 0.5}, {0.5, 0.5}}) {
          const Vec3 d = Vec3(x + dx * pixel, y + dy * pixel, z) - c;
          const double r = glm::length(d);
          if (!(r > unclassified_m)) {
            std::fill(reached.begin(), reached.end(), 1);
            break;
          }
          for (std::size_t t = 0; t < thresholds; ++t) {
            if (reached[t] == 0 && r <= reachToward(near, far, t, d / r, extinction_per_m))
              reached[t] = 1;
          }
        }
        if (std::none_of(reached.begin(), reached.end(), [](char v) { return v != 0; })) continue;
        if (terrain != nullptr && !terrain->segmentClear(c, {x, y, z})) {
          if (reached[0] != 0) ++row.hidden;
          continue;
        }
        for (std::size_t t = 0; t < thresholds; ++t) {
          if (reached[t] == 0) continue;
          inside[t][k] = 1;
          ++row.inside[t];
        }
      }
      if (counter != nullptr) counter->items_done.fetch_add(1, std::memory_order_relaxed);
    });
    std::vector<std::size_t> inside_pixels(thresholds, 0);
    for (const RowCount& row : rows) {
      hidden += row.hidden;
      for (std::size_t t = 0; t < thresholds; ++t) inside_pixels[t] += row.inside[t];
    }
    area_m2.assign(thresholds, 0.0);
    for (std::size_t t = 0; t < thresholds; ++t)
      area_m2[t] = static_cast<double>(inside_pixels[t]) * pixel * pixel;
  };
  for (std::size_t k = 0; k < count; ++k)
    f.ground_z_m[k] = static_cast<float>(ground_m[k] + spec.above_ground_m);
  cover([&](std::size_t k, double, double) { return ground_m[k] + spec.above_ground_m; }, f.inside,
        f.area_m2, f.hidden_pixels);
  for (const double altitude_m : spec.flight_altitudes_m) {
    ReachFootprint::Altitude& a = f.altitudes.emplace_back();
    a.altitude_m = altitude_m;
    // Above the ellipsoid: the local frame's z of that geodetic height under the pixel.
    const auto above_ellipsoid = [&](std::size_t, double x, double y) {
      const SiteFrame& frame = localSite();
      const Geodetic here = frame.toGeodetic({x, y, 0.0});
      return frame.fromGeodetic({here.latitude_deg, here.longitude_deg, altitude_m}).z;
    };
    const auto above_ground = [&](std::size_t k, double, double) {
      return ground_m[k] + altitude_m;
    };
    if (spec.altitudes_above_ellipsoid) {
      cover(above_ellipsoid, a.inside, a.area_m2, a.hidden_pixels);
    } else {
      cover(above_ground, a.inside, a.area_m2, a.hidden_pixels);
    }
  }
  return f;
}

}  // namespace glint
