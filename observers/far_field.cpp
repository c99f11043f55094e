// The far field: six adaptive observer planes far beyond the far radius, read as intensity.
#include "observers/far_field.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace glint {
namespace {

// The largest float: maps store distances and intensities as float, capped here.
constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());

// Outward normal, u and v of each cube face (u × v = normal: the plane's lattice axes).
struct FaceFrame {
  Vec3 normal, u, v;
};
const std::array<FaceFrame, FarField::kFaces> kFaceFrames = {{
    {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}},
    {{-1, 0, 0}, {0, -1, 0}, {0, 0, 1}},
    {{0, 1, 0}, {0, 0, 1}, {1, 0, 0}},
    {{0, -1, 0}, {0, 0, -1}, {1, 0, 0}},
    {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}},
    {{0, 0, -1}, {-1, 0, 0}, {0, 1, 0}},
}};

// The map is integrated this many far radii out: its own parallax error is then a thousandth
// of the tolerance (farRadius()), while positions keep ~1e-9 relative precision.
constexpr double kMapDistanceInFarRadii = 1e3;

// The hazard surface draws a point whose far radius exceeds this many times the smallest (in
// the forward cone) at that limit: the surface stays finite.
constexpr double kForwardDisplayLimit = 10.0;

// The face whose cone holds @p d, and where d crosses it in lattice units (0 .. face_pixels).
struct FaceHit {
  int face = 0;
  double x = 0.0, y = 0.0;
};
FaceHit faceHit(const Vec3& d, int face_pixels) {
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(d[a]) > std::abs(d[axis])) axis = a;
  }
  FaceHit h;
  h.face = 2 * axis + (d[axis] < 0.0 ? 1 : 0);
  const FaceFrame& f = kFaceFrames[static_cast<std::size_t>(h.face)];
  const double t = 1.0 / glm::dot(d, f.normal);  // > 0: the dominant axis
  const double half = 0.5 * face_pixels;
  h.x = std::clamp((t * glm::dot(d, f.u) + 1.0) * half, 0.0, 2.0 * half);
  h.y = std::clamp((t * glm::dot(d, f.v) + 1.0) * half, 0.0, 2.0 * half);
  return h;
}

// The direction of the centre of pixel @p p of a width × height lat-long map (latLongMap()).
Vec3 latLongDirection(std::size_t p, int width, int height) {
  const auto w = static_cast<std::size_t>(width);
  const double elevation = -0.5 * kPi + (static_cast<double>(p / w) + 0.5) * kPi / height;
  const double azimuth = -kPi + (static_cast<double>(p % w) + 0.5) * 2.0 * kPi / width;
  return {std::cos(elevation) * std::cos(azimuth), std::cos(elevation) * std::sin(azimuth),
          std::sin(elevation)};
}

bool powerOfTwo(int n) { return n > 0 && (n & (n - 1)) == 0; }

void validate(const FarFieldSpec& s) {
  if (!powerOfTwo(s.face_pixels) || s.face_pixels < 16 || s.face_pixels > 8192 ||
      !powerOfTwo(s.block_pixels) || s.block_pixels > s.face_pixels ||
      !(s.tolerance > 0.0 && s.tolerance < 1.0) || !(s.floor_w_sr >= 0.0) ||
      !std::isfinite(s.floor_w_sr) || !(s.far_radius_m > 0.0) || !std::isfinite(s.far_radius_m)) {
    throw std::invalid_argument("FarFieldSpec out of range");
  }
}

// The intensity of a direction that is not a finite number counts as +∞: a NaN must never
// read as "no hazard" in a maximum.
double hazardSafe(double intensity_w_sr) {
  return std::isnan(intensity_w_sr) ? std::numeric_limits<double>::infinity() : intensity_w_sr;
}

}  // namespace

LitBall litBall(const FacetIntegrator& integrator) {
  const std::span<const Candidate> lit = integrator.candidates();
  if (lit.empty()) return {};
  const Target& target = integrator.target();
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const Candidate& c : lit) {
    const Vec3 origin = target.objects[c.object].origin_m;
    for (const Vec3& corner : c.geometry.corner_m) {
      lo = glm::min(lo, origin + corner);
      hi = glm::max(hi, origin + corner);
    }
  }
  LitBall ball{0.5 * (lo + hi), 0.0};
  for (const Candidate& c : lit) {
    const Vec3 centre = target.objects[c.object].origin_m + c.geometry.centre_m;
    ball.radius_m =
        std::max(ball.radius_m, glm::length(centre - ball.centre_m) + c.geometry.radius_m);
  }
  return ball;
}

double farRadius(double lit_radius_m, double narrowest_sigma, double tolerance,
                 double forward_angle_rad) {
  // sin(ψ/2) ≤ 0 only exactly forward: the bound is then infinite, as it should be.
  const double half_vector_gain = std::max(1.0, 0.43 / std::sin(0.5 * forward_angle_rad));
  const double rate_per_rad =
      3.0 + (std::isfinite(narrowest_sigma) ? half_vector_gain / narrowest_sigma : 0.0);
  return lit_radius_m * (1.0 + rate_per_rad / tolerance);
}

double farRadiusToward(const FarFieldSpec& spec, const Vec3& direction) {
  const double psi = std::acos(std::clamp(glm::dot(direction, spec.beam_direction), -1.0, 1.0));
  const double r = farRadius(spec.lit_radius_m, spec.narrowest_sigma, spec.tolerance, psi);
  return std::isnan(r) ? std::numeric_limits<double>::infinity() : std::max(r, spec.far_radius_m);
}

double hazardDistance(double intensity_w_sr, double threshold_w_m2, double extinction_per_m,
                      double source_radius_m) {
  if (!std::isfinite(intensity_w_sr)) return std::numeric_limits<double>::infinity();
  if (!(intensity_w_sr > 0.0)) return 0.0;
  const double vacuum_m = std::sqrt(intensity_w_sr / threshold_w_m2);
  if (!(extinction_per_m > 0.0) || vacuum_m <= source_radius_m) return vacuum_m;
  // I T(r) / r² falls with r: bisect its logarithm's crossing between the source's edge and
  // the vacuum distance.
  const double log_ratio = std::log(intensity_w_sr / threshold_w_m2);
  auto above = [&](double r) {
    return log_ratio - extinction_per_m * (r - source_radius_m) - 2.0 * std::log(r) >= 0.0;
  };
  double lo = std::max(0.0, source_radius_m), hi = vacuum_m;  // above at lo: I/a² > threshold
  for (int i = 0; i < 200 && hi - lo > 1e-12 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (above(mid) ? lo : hi) = mid;
  }
  return hi;  // the upper end: never nearer than the crossing
}

FarReach farReach(const FarField& field, double mpe_w_m2, double extinction_per_m) {
  FarReach reach;
  reach.direction = field.peak().direction;
  reach.far_radius_m = farRadiusToward(field.spec(), reach.direction);
  const double source_m = field.ball().radius_m;
  double best_w_sr = 0.0;  // the distance grows with intensity: only a brighter one can beat it
  field.forEachDirection([&](const Vec3& d, double intensity_w_sr) {
    const double intensity = hazardSafe(intensity_w_sr);
    if (!(intensity > best_w_sr)) return;
    const double nohd = hazardDistance(intensity, mpe_w_m2, extinction_per_m, source_m);
    const double far_m = farRadiusToward(field.spec(), d);
    if (nohd >= far_m) {
      reach = {nohd, d, far_m};
      best_w_sr = intensity;
    }
  });
  return reach;
}

FieldSpec cubeFaceSpec(int face, const Vec3& centre_m, double distance_m,
                       const FarFieldSpec& spec) {
  const FaceFrame& f = kFaceFrames.at(static_cast<std::size_t>(face));
  FieldSpec s;
  s.plane = true;
  s.axes = {f.u, f.v, f.normal};
  s.min_m = centre_m + distance_m * (f.normal - f.u - f.v);
  s.max_m = centre_m + distance_m * (f.normal + f.u + f.v);
  s.voxel_m = 2.0 * distance_m / spec.face_pixels;
  s.block_voxels = spec.block_pixels;
  s.tolerance = spec.tolerance;
  // Irradiance at the faces' corners (√3 × the distance) stands for 3 d² × as much intensity:
  // the floor holds for intensity everywhere on the face.
  s.floor_w_m2 = spec.floor_w_sr / (3.0 * distance_m * distance_m);
  s.bound_split_depth = spec.bound_split_depth;
  return s;
}

FarField::Face::Face(const ObserverField& field)
    : spec(field.spec()), stats(field.stats()), irradiance_w_m2(field.irradianceLattice()) {}

FarField::FarField(LitBall ball, FarFieldSpec spec, double map_distance_m, std::vector<Face> faces)
    : ball_(ball), spec_(spec), map_distance_m_(map_distance_m), faces_(std::move(faces)) {
  for (const Face& face : faces_) {
    const FieldStats& s = face.stats;
    stats_.lattice_points += s.lattice_points;
    stats_.evaluated_points += s.evaluated_points;
    stats_.interpolated_points += s.interpolated_points;
    stats_.below_floor_points += s.below_floor_points;
    stats_.excluded_points += s.excluded_points;
    stats_.unconverged_points += s.unconverged_points;
    stats_.non_finite_points += s.non_finite_points;
    if (s.non_finite_points > 0) stats_.non_finite_at_m = s.non_finite_at_m;
    // In intensity: no point of a face is farther than √3 × the distance.
    stats_.unconverged_max_upper_w_m2 =
        std::max(stats_.unconverged_max_upper_w_m2,
                 hazardSafe(s.unconverged_max_upper_w_m2) * 3.0 * map_distance_m * map_distance_m);
    stats_.blocks_skipped += s.blocks_skipped;
    stats_.blocks_accepted += s.blocks_accepted;
    stats_.blocks_accepted_spread += s.blocks_accepted_spread;
    stats_.blocks_refined += s.blocks_refined;
    stats_.blocks_finest += s.blocks_finest;
    stats_.evaluations += s.evaluations;
    stats_.bound_evaluations += s.bound_evaluations;
    stats_.levels = std::max(stats_.levels, s.levels);
    stats_.seconds += s.seconds;
    stats_.active_voxels += s.active_voxels;
    stats_.grid_bytes += s.grid_bytes;
  }
  peak_.intensity_w_sr = 0.0;
  forEachDirection([&](const Vec3& d, double intensity_w_sr) {
    if (hazardSafe(intensity_w_sr) > peak_.intensity_w_sr) peak_ = {intensity_w_sr, d};
  });
}

Vec3 FarField::latticePoint(int face, int i, int j) const {
  return faces_[static_cast<std::size_t>(face)].spec.position(i, j, 0);
}

double FarField::latticeIntensity(int face, int i, int j) const {
  const double d = glm::length(latticePoint(face, i, j) - ball_.centre_m);
  const Face& f = faces_[static_cast<std::size_t>(face)];
  const auto row = static_cast<std::size_t>(spec_.face_pixels) + 1;
  return static_cast<double>(
             f.irradiance_w_m2[static_cast<std::size_t>(j) * row + static_cast<std::size_t>(i)]) *
         d * d;
}

double FarField::intensity(const Vec3& direction) const {
  const FaceHit h = faceHit(direction, spec_.face_pixels);
  const int i = std::min(static_cast<int>(h.x), spec_.face_pixels - 1);
  const int j = std::min(static_cast<int>(h.y), spec_.face_pixels - 1);
  const double fx = h.x - i, fy = h.y - j;
  return (1.0 - fy) * ((1.0 - fx) * latticeIntensity(h.face, i, j) +
                       fx * latticeIntensity(h.face, i + 1, j)) +
         fy * ((1.0 - fx) * latticeIntensity(h.face, i, j + 1) +
               fx * latticeIntensity(h.face, i + 1, j + 1));
}

FarField computeFarField(const FacetIntegrator& integrator, const FarFieldSpec& spec,
                         WorkCounter* counter, PointExchange* exchange) {
  validate(spec);
  const LitBall ball = litBall(integrator);
  const double distance_m = kMapDistanceInFarRadii * spec.far_radius_m;
  std::vector<FarField::Face> faces;
  faces.reserve(FarField::kFaces);
  for (int f = 0; f < FarField::kFaces; ++f) {
    const FieldSpec face = cubeFaceSpec(f, ball.centre_m, distance_m, spec);
    // A quarter of the map's tolerance and floor, as for every observer field
    // (fieldIntegratorOptions()). Intensity is read unattenuated along the reflected paths:
    // the air's share is the hazard distance's (hazardDistance()).
    const FacetIntegrator at_face =
        integrator.withAccuracy(0.25 * face.tolerance, 0.25 * face.floor_w_m2)
            .withReturnExtinction(0.0);
    // Each face's grids are dropped as soon as its lattice is taken.
    faces.emplace_back(computeField(at_face, face, ExcludedFn(), counter, exchange));
  }
  return {ball, spec, distance_m, std::move(faces)};
}

LatLongMap latLongMap(const FarField& field, int height, double mpe_w_m2, double extinction_per_m,
                      double aided_mpe_w_m2) {
  LatLongMap m;
  m.height = height;
  m.width = 2 * height;
  const auto w = static_cast<std::size_t>(m.width);
  m.intensity_w_sr.assign(w * static_cast<std::size_t>(height), 0.0f);
  std::vector<double> cell(m.intensity_w_sr.size(), 0.0);
  for (std::size_t p = 0; p < cell.size(); ++p) {
    cell[p] = hazardSafe(field.intensity(latLongDirection(p, m.width, height)));
  }
  field.forEachDirection([&](const Vec3& d, double intensity_w_sr) {
    const double azimuth = std::atan2(d.y, d.x);
    const double elevation = std::asin(std::clamp(d.z, -1.0, 1.0));
    const int i =
        std::clamp(static_cast<int>((azimuth + kPi) / (2.0 * kPi) * m.width), 0, m.width - 1);
    const int j =
        std::clamp(static_cast<int>((elevation + 0.5 * kPi) / kPi * height), 0, height - 1);
    double& c = cell[static_cast<std::size_t>(j) * w + static_cast<std::size_t>(i)];
    c = std::max(c, hazardSafe(intensity_w_sr));
  });
  // The hazard distance toward the pixel where it lies beyond the far radius there, else 0.
  const double source_m = field.ball().radius_m;
  auto reach = [&](double intensity, double threshold_w_m2, const Vec3& d) {
    const double nohd = hazardDistance(intensity, threshold_w_m2, extinction_per_m, source_m);
    return nohd >= farRadiusToward(field.spec(), d) ? static_cast<float>(std::min(nohd, kFloatMax))
                                                    : 0.0f;
  };
  m.nohd_m.resize(cell.size());
  if (aided_mpe_w_m2 > 0.0) m.aided_nohd_m.resize(cell.size());
  for (std::size_t p = 0; p < cell.size(); ++p) {
    const Vec3 d = latLongDirection(p, m.width, height);
    m.intensity_w_sr[p] = static_cast<float>(std::min(cell[p], kFloatMax));
    m.nohd_m[p] = reach(cell[p], mpe_w_m2, d);
    if (aided_mpe_w_m2 > 0.0) m.aided_nohd_m[p] = reach(cell[p], aided_mpe_w_m2, d);
  }
  return m;
}

HazardSurface hazardSurface(const FarField& field, int cells_per_face, double mpe_w_m2,
                            double extinction_per_m) {
  const int n = field.spec().face_pixels;
  const int m = std::clamp(cells_per_face, 1, n);
  const int step = n / m;  // both powers of two
  const auto vertices = static_cast<std::size_t>(m + 1) * static_cast<std::size_t>(m + 1);
  HazardSurface s;
  const Vec3 centre = field.ball().centre_m;
  for (int f = 0; f < FarField::kFaces; ++f) {
    const FarField::Face& face = field.faces()[static_cast<std::size_t>(f)];
    // Each lattice direction lends its intensity to the nearest vertex.
    std::vector<double> vertex_max(vertices, 0.0);
    field.forEachDirectionOfFace(f, [&](int i, int j, const Vec3&, double intensity_w_sr) {
      const int a = (i + step / 2) / step, b = (j + step / 2) / step;
      double& v = vertex_max[static_cast<std::size_t>(b) * (m + 1) + static_cast<std::size_t>(a)];
      v = std::max(v, hazardSafe(intensity_w_sr));
    });
    const auto first = static_cast<std::int64_t>(s.points_m.size());
    for (int b = 0; b <= m; ++b)
      for (int a = 0; a <= m; ++a) {
        const Vec3 p = face.spec.position(a * step, b * step, 0);
        const Vec3 dir = glm::normalize(p - centre);
        const double intensity =
            vertex_max[static_cast<std::size_t>(b) * (m + 1) + static_cast<std::size_t>(a)];
        const double nohd =
            hazardDistance(intensity, mpe_w_m2, extinction_per_m, field.ball().radius_m);
        const double far_m = farRadiusToward(field.spec(), dir);
        const bool beyond = nohd >= far_m;
        // The far radius grows without bound toward the beam's own direction: drawn capped.
        const double shown_m =
            beyond ? nohd : std::min(far_m, kForwardDisplayLimit * field.spec().far_radius_m);
        s.points_m.push_back(centre + shown_m * dir);
        s.nohd_m.push_back(beyond ? static_cast<float>(std::min(nohd, kFloatMax)) : 0.0f);
        s.intensity_w_sr.push_back(static_cast<float>(std::min(intensity, kFloatMax)));
        s.beyond_far_radius.push_back(beyond ? 1 : 0);
      }
    const auto at = [&](int a, int b) {
      return first + static_cast<std::int64_t>(b) * (m + 1) + a;
    };
    for (int b = 0; b < m; ++b)
      for (int a = 0; a < m; ++a)
        s.quads.push_back({at(a, b), at(a + 1, b), at(a + 1, b + 1), at(a, b + 1)});
  }
  return s;
}

}  // namespace glint
