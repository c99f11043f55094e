// The hazard reach: six radial lattices from the target out to the far radius, and the far
// field beyond.
#include "observers/reach.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "observers/detail/cube_faces.h"
#include "observers/far_field.h"

namespace glint {
namespace {

constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());

std::size_t rayIndex(int i, int j, int face_cells) {
  return static_cast<std::size_t>(j) * static_cast<std::size_t>(face_cells + 1) +
         static_cast<std::size_t>(i);
}

// The far field's hazard distance toward unit @p d where it is at least the far radius there
// (nearer, the lattice decides), else 0.
double farReachToward(const FarField& far, double threshold_w_m2, double extinction_per_m,
                      const Vec3& d) {
  const double r =
      far.hazardDistanceToward(d, far.upperIntensity(d), threshold_w_m2, extinction_per_m);
  return r >= farRadiusToward(far.spec(), d) ? r : 0.0;
}

}  // namespace

double reachStartM(const ReachSpec& spec) { return spec.near_m / (spec.inner_layers + 1); }

FieldSpec reachFaceSpec(int face, const ReachSpec& spec) {
  const cube::FaceFrame& frame = cube::kFaceFrames.at(static_cast<std::size_t>(face));
  FieldSpec s;
  s.axes = {frame.u, frame.v, frame.normal};
  s.voxel_m = 1.0;  // unused by a radial lattice
  s.block_voxels = spec.block_voxels;
  s.tolerance = spec.tolerance;
  s.floor_w_m2 = spec.floor_w_m2;
  s.hazard_threshold_w_m2 =
      spec.thresholds_w_m2.empty()
          ? 0.0
          : *std::min_element(spec.thresholds_w_m2.begin(), spec.thresholds_w_m2.end());
  // Only whether points are hazardous is read (computeNearReach()): a block hazardous at
  // every sample for the highest threshold is taken whole, a hair above it so that its
  // interpolated points, rounded to float, stay so.
  if (!spec.thresholds_w_m2.empty()) {
    s.classify_above_w_m2 =
        (1.0 - spec.tolerance) *
        *std::max_element(spec.thresholds_w_m2.begin(), spec.thresholds_w_m2.end()) * (1.0 + 1e-6);
  }
  const int inner = spec.inner_layers;
  const double outer = std::ceil(std::log(spec.far_m / spec.near_m) / std::log(spec.ratio));
  const int b = spec.block_voxels;
  const int whole = std::max(b, static_cast<int>(std::ceil((inner + outer) / b)) * b);
  s.radial = RadialLattice{spec.centre_m, spec.face_cells, spec.near_m,      spec.ratio,
                           whole,         inner,           reachStartM(spec)};
  return s;
}

double NearReach::toward(const Vec3& direction, std::size_t t) const {
  const int n = spec.face_cells;
  const cube::FaceHit h = cube::faceHit(direction, n);
  const int i = std::clamp(static_cast<int>(std::floor(h.x)), 0, n - 1);
  const int j = std::clamp(static_cast<int>(std::floor(h.y)), 0, n - 1);
  const std::vector<float>& r = faces[static_cast<std::size_t>(h.face)].reach_m[t];
  // The layers are planes: a ray's reach is a layer's plane distance times its stretch, and a
  // point of the cell between the rays lies no farther than that plane along its own direction.
  const double step = 2.0 / n;
  double plane_m = 0.0;
  for (int c = 0; c < 4; ++c) {
    const int a = i + (c & 1), b = j + (c >> 1);
    const double u = -1.0 + step * a, v = -1.0 + step * b;
    plane_m = std::max(plane_m,
                       static_cast<double>(r[rayIndex(a, b, n)]) / std::sqrt(1.0 + u * u + v * v));
  }
  const double cos_n =
      glm::dot(direction, cube::kFaceFrames[static_cast<std::size_t>(h.face)].normal);
  return plane_m / cos_n;
}

double NearReach::lastLayerToward(const Vec3& direction) const {
  const cube::FaceHit h = cube::faceHit(direction, spec.face_cells);
  const RadialLattice& r = *faces[static_cast<std::size_t>(h.face)].spec.radial;
  // The layers are planes: along d their distance grows as 1 / (d · n).
  const double cos_n =
      glm::dot(direction, cube::kFaceFrames[static_cast<std::size_t>(h.face)].normal);
  return r.layerDistance(r.layers) / cos_n;
}

std::int64_t NearReach::evaluatedPoints() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.stats.evaluated_points;
  return n;
}

std::int64_t NearReach::evaluations() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.stats.evaluations;
  return n;
}

std::int64_t NearReach::unresolvedPoints() const {
  std::int64_t n = 0;
  for (const Face& f : faces) n += f.stats.unresolved_points;
  return n;
}

NearReach computeNearReach(const FacetIntegrator& integrator, const ReachSpec& spec,
                           const ExcludedFn& excluded, WorkCounter* counter,
                           PointExchange* exchange) {
  NearReach near;
  near.spec = spec;
  const std::size_t thresholds = spec.thresholds_w_m2.size();
  near.volume_m3.assign(thresholds, 0.0);
  std::vector<double> hazardous_w_m2;
  for (const double t : spec.thresholds_w_m2) hazardous_w_m2.push_back((1.0 - spec.tolerance) * t);
  for (int f = 0; f < cube::kFaces; ++f) {
    NearReach::Face& out = near.faces[static_cast<std::size_t>(f)];
    out.spec = reachFaceSpec(f, spec);
    const ObserverField field = computeField(integrator, out.spec, excluded, counter, exchange);
    out.stats = field.stats();
    const RadialLattice& r = *out.spec.radial;
    const int n = r.face_cells;
    const std::size_t rays = rayIndex(n, n, n) + 1;
    out.reach_m.assign(thresholds, std::vector<float>(rays, 0.0f));
    out.peak_w_m2.assign(rays, 0.0f);
    // Each lattice point read once: bit t says whether it counts as hazardous for threshold t.
    // An Unresolved point may have a glint beside it that its lattice cannot see; an
    // Unconverged one may be short of its value by its error, which the field keeps only as
    // the largest value plus error of them all; the target's inside is no place.
    const double unconverged_upper_w_m2 = out.stats.unconverged_max_upper_w_m2;
    const int layers = r.layers + 1;
    const auto at = [&](int i, int j, int k) {
      return (rayIndex(i, j, n) * static_cast<std::size_t>(layers)) + static_cast<std::size_t>(k);
    };
    std::vector<std::uint8_t> hazard_bits(rays * static_cast<std::size_t>(layers), 0);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        double peak = 0.0;
        for (int k = 0; k <= r.layers; ++k) {
          const VoxelStatus s = field.status(i, j, k);
          if (s == VoxelStatus::Excluded) continue;
          const double e = field.irradiance(i, j, k);
          peak = std::max(peak, e);
          std::uint8_t bits = 0;
          for (std::size_t t = 0; t < thresholds; ++t) {
            const bool hazardous =
                s == VoxelStatus::Unresolved || e >= hazardous_w_m2[t] ||
                (s == VoxelStatus::Unconverged && unconverged_upper_w_m2 >= hazardous_w_m2[t]);
            bits = static_cast<std::uint8_t>(bits | (hazardous ? 1u << t : 0u));
          }
          hazard_bits[at(i, j, k)] = bits;
        }
        out.peak_w_m2[rayIndex(i, j, n)] = static_cast<float>(peak);
      }
    const auto hazardous = [&](int i, int j, int k, std::size_t t) {
      return ((hazard_bits[at(i, j, k)] >> t) & 1u) != 0;
    };
    const double step = 2.0 / n;
    std::vector<double> volume(thresholds, 0.0);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double u = -1.0 + step * i, v = -1.0 + step * j;
        const double stretch = std::sqrt(1.0 + u * u + v * v);  // distance / ρ along this ray
        const std::size_t ray = rayIndex(i, j, n);
        for (std::size_t t = 0; t < thresholds; ++t) {
          for (int k = r.layers; k >= 0; --k) {
            if (!hazardous(i, j, k, t)) continue;
            out.reach_m[t][ray] =
                static_cast<float>(stretch * r.layerDistance(std::min(k + 1, r.layers)));
            break;
          }
        }
        if (i == n || j == n) continue;
        // Cell (i, j, k) holds ρ² dρ du dv: (ρ1³ − ρ0³) / 3 × step², weighted by the share of
        // its eight corners that are hazardous.
        for (int k = 0; k < r.layers; ++k) {
          const double a = r.layerDistance(k), b = r.layerDistance(k + 1);
          const double cell_m3 = step * step * (b * b * b - a * a * a) / 3.0;
          for (std::size_t t = 0; t < thresholds; ++t) {
            int corners = 0;
            for (int c = 0; c < 8; ++c)
              corners += hazardous(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2), t) ? 1 : 0;
            volume[t] += cell_m3 * corners / 8.0;
          }
        }
      }
    for (std::size_t t = 0; t < thresholds; ++t) near.volume_m3[t] += volume[t];
  }
  return near;
}

double reachToward(const NearReach& near, const FarField& far, std::size_t t, const Vec3& direction,
                   double extinction_per_m) {
  return std::max(near.toward(direction, t), farReachToward(far, near.spec.thresholds_w_m2.at(t),
                                                            extinction_per_m, direction));
}

ReachSummary summarizeReach(const NearReach& near, const FarField& far, std::size_t t,
                            double extinction_per_m) {
  ReachSummary s;
  s.threshold_w_m2 = near.spec.thresholds_w_m2.at(t);
  // The farthest of what toward() gives over every direction: within a lattice cell, the
  // farthest layer plane of its four rays taken along the cell's most oblique corner, which
  // lies beyond every one of the four rays' own reach where the farthest plane is not that
  // corner's.
  const int n = near.spec.face_cells;
  const double step = 2.0 / n;
  for (int f = 0; f < cube::kFaces; ++f) {
    const std::vector<float>& r = near.faces[static_cast<std::size_t>(f)].reach_m[t];
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        double plane_m = 0.0, stretch = 0.0;
        int corner_i = i, corner_j = j;
        for (int c = 0; c < 4; ++c) {
          const int a = i + (c & 1), b = j + (c >> 1);
          const double u = -1.0 + step * a, v = -1.0 + step * b;
          const double k = std::sqrt(1.0 + u * u + v * v);
          plane_m = std::max(plane_m, static_cast<double>(r[rayIndex(a, b, n)]) / k);
          if (k > stretch) {
            stretch = k;
            corner_i = a;
            corner_j = b;
          }
        }
        const double d = plane_m * stretch;
        if (d > s.distance_m) {
          s.distance_m = d;
          s.direction = cube::planeDirection(f, corner_i, corner_j, n);
        }
      }
  }
  const FarReach beyond = farReach(far, s.threshold_w_m2, extinction_per_m);
  if (beyond.nohd_m > s.distance_m) {
    s.distance_m = beyond.nohd_m;
    s.direction = beyond.direction;
    s.from_far_field = true;
  }
  // Beyond each direction's last layer, the shell out to the far field's hazard distance,
  // over the map's lattice directions (their solid angles by the trapezoid rule on each face).
  const int m = far.spec().face_pixels;
  const double h = 2.0 / m;
  double shell_m3 = 0.0;
  for (int f = 0; f < FarField::kFaces; ++f) {
    far.forEachDirectionOfFace(f, [&](int i, int j, const Vec3& d, double intensity_w_sr) {
      const double r =
          far.hazardDistanceToward(d, intensity_w_sr, s.threshold_w_m2, extinction_per_m);
      const double last = near.lastLayerToward(d);
      if (!(r > last) || !std::isfinite(r)) return;
      const double u = -1.0 + h * i, v = -1.0 + h * j;
      const double weight = (i == 0 || i == m ? 0.5 : 1.0) * (j == 0 || j == m ? 0.5 : 1.0);
      const double solid_angle = weight * h * h / std::pow(1.0 + u * u + v * v, 1.5);
      shell_m3 += solid_angle * (r * r * r - last * last * last) / 3.0;
    });
  }
  s.unclassified_half_edge_m = reachStartM(near.spec);
  s.unclassified_m3 = 8.0 * std::pow(s.unclassified_half_edge_m, 3);
  s.volume_m3 = near.volume_m3.at(t) + shell_m3 + s.unclassified_m3;
  if (std::isfinite(s.distance_m))
    s.farthest_point_m = near.spec.centre_m + s.distance_m * s.direction;
  // The lattice reaches the far radius along every ray; beyond it the far field answers for
  // every direction only where its radius is one (verified) and every glint is bounded.
  s.closed = std::isfinite(s.distance_m) && far.spec().far_radius_verified &&
             near.spec.far_m >= far.spec().far_radius_m;
  return s;
}

std::vector<float> reachLatLong(const NearReach& near, const FarField& far, std::size_t t,
                                int height, double extinction_per_m) {
  const double threshold = near.spec.thresholds_w_m2.at(t);
  // The far field's largest hazard distance over each pixel (0 where it ends inside r_far).
  const LatLongMap beyond = latLongMap(far, height, threshold, extinction_per_m);
  std::vector<float> reach(beyond.nohd_m.size());
  tbb::parallel_for(std::size_t{0}, reach.size(), [&](std::size_t p) {
    const Vec3 d = cube::latLongDirection(p, beyond.width, beyond.height);
    const double r = std::max(near.toward(d, t), static_cast<double>(beyond.nohd_m[p]));
    reach[p] = static_cast<float>(std::min(r, kFloatMax));
  });
  return reach;
}

ReachSurface reachSurface(const NearReach& near, const FarField& far, double extinction_per_m) {
  ReachSurface s;
  const int n = near.spec.face_cells;
  const double threshold = near.spec.thresholds_w_m2.at(0);
  const Vec3 centre = near.spec.centre_m;
  const auto row = static_cast<std::int64_t>(n + 1);
  for (int f = 0; f < cube::kFaces; ++f) {
    const NearReach::Face& face = near.faces[static_cast<std::size_t>(f)];
    const auto base = static_cast<std::int64_t>(s.points_m.size());
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const Vec3 d = cube::planeDirection(f, i, j, n);
        const std::size_t ray = rayIndex(i, j, n);
        const double beyond = farReachToward(far, threshold, extinction_per_m, d);
        const double r = std::max(static_cast<double>(face.reach_m[0][ray]), beyond);
        // A glint the far field could not bound has no distance to draw: its point stays at
        // the lattice's end, and its distance reads as the largest float.
        s.points_m.push_back(centre + (std::isfinite(r) ? r : near.lastLayerToward(d)) * d);
        s.distance_m.push_back(static_cast<float>(std::min(r, kFloatMax)));
        s.hazard_ratio.push_back(
            static_cast<float>(static_cast<double>(face.peak_w_m2[ray]) / threshold));
      }
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const std::int64_t a = base + j * row + i;
        s.quads.push_back({a, a + 1, a + 1 + row, a + row});
      }
  }
  return s;
}

}  // namespace glint
