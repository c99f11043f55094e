// The far field: six adaptive observer planes far beyond the far radius, read as intensity.
#include "observers/far_field.h"

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

#include "observers/block_check.h"
#include "observers/detail/cube_faces.h"

namespace glint {
namespace {

using cube::FaceFrame;
using cube::FaceHit;
using cube::faceHit;
using cube::kFaceFrames;
using cube::latLongDirection;
using cube::onFacePlane;
using cube::planeDirection;
using cube::PlanePoint;

// The largest float: maps store distances and intensities as float, capped here.
constexpr double kFloatMax = static_cast<double>(std::numeric_limits<float>::max());

// The map is integrated this many far radii out: its own parallax error is then a thousandth
// of the tolerance (farRadius()), while positions keep ~1e-9 relative precision.
constexpr double kMapDistanceInFarRadii = 1e3;

// The hazard surface draws a point whose far radius exceeds this many times the smallest (in
// the forward cone) at that limit: the surface stays finite.
constexpr double kForwardDisplayLimit = 10.0;

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

// The angle between lattice directions at face point (x, y) (lattice units), at least: a
// lattice step turns the direction by 2/N / (1 + X² + Y²) or more, X and Y in −1 .. 1.
double latticeAngle(double x, double y, int face_pixels) {
  const double half = 0.5 * face_pixels;
  const double u = x / half - 1.0, v = y / half - 1.0;
  return (2.0 / face_pixels) / (1.0 + u * u + v * v);
}

// The key of the finest block (2 × 2 lattice cells) at lattice origin (2 a, 2 b) of a face.
std::uint64_t narrowKey(int a, int b, int face_pixels) {
  return static_cast<std::uint64_t>(a) * static_cast<std::uint64_t>(face_pixels) +
         static_cast<std::uint64_t>(b);
}

}  // namespace

double farRadius(double lit_radius_m, double narrowest_sigma, double tolerance,
                 double forward_angle_rad) {
  // sin(ψ/2) ≤ 0 only exactly forward: the bound is then infinite, as it should be.
  const double half_vector_gain = std::max(1.0, 0.43 / std::sin(0.5 * forward_angle_rad));
  const double rate_per_rad =
      3.0 + (std::isfinite(narrowest_sigma) ? half_vector_gain / narrowest_sigma : 0.0);
  return lit_radius_m * (1.0 + rate_per_rad / tolerance);
}

double farRadiusToward(const FarFieldSpec& spec, const Vec3& direction) {
  if (spec.far_radius_verified) return spec.far_radius_m;
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

std::vector<FarReach> farReaches(const FarField& field, std::span<const double> thresholds_w_m2,
                                 double extinction_per_m) {
  const std::size_t count = thresholds_w_m2.size();
  FarReach none;
  none.direction = field.peak().direction;
  none.far_radius_m = farRadiusToward(field.spec(), none.direction);
  std::vector<FarReach> reach(count, none);
  // Each direction's intensity and its allowance are found once for every threshold.
  const auto consider = [&](std::vector<FarReach>& best, std::size_t first, const Vec3& d,
                            double intensity_w_sr) {
    const double judged_w_sr = field.hazardIntensityToward(d, intensity_w_sr);
    for (std::size_t t = 0; t < count; ++t) {
      FarReach& r = best[first + t];
      const double nohd =
          hazardDistance(judged_w_sr, thresholds_w_m2[t], extinction_per_m, field.ball().radius_m);
      if (!(nohd > r.nohd_m)) continue;
      const double far_m = farRadiusToward(field.spec(), d);
      if (nohd >= far_m) r = {nohd, d, far_m};
    }
  };
  // The located tops first: a lattice direction beside one, as bright by its allowance, does
  // not take its place.
  for (const FarField::Peak& p : field.located()) consider(reach, 0, p.direction, p.intensity_w_sr);
  for (const FarField::Peak& p : field.narrowGlints())
    consider(reach, 0, p.direction, p.intensity_w_sr);
  // The lattice's directions, each face's rows in parallel: a row's farthest, then the rows'
  // in order, each replacing only a strictly farther one, as one pass in order would.
  const int n = field.spec().face_pixels;
  const std::size_t row_count = static_cast<std::size_t>(FarField::kFaces) * (n + 1);
  std::vector<FarReach> rows(row_count * count);
  tbb::parallel_for(std::size_t{0}, row_count, [&](std::size_t r) {
    const int f = static_cast<int>(r / static_cast<std::size_t>(n + 1));
    const int j = static_cast<int>(r % static_cast<std::size_t>(n + 1));
    for (int i = 0; i <= n; ++i) {
      consider(rows, r * count, field.latticeDirection(f, i, j),
               field.latticeUpperIntensity(f, i, j));
    }
  });
  for (std::size_t r = 0; r < row_count; ++r)
    for (std::size_t t = 0; t < count; ++t) {
      if (rows[r * count + t].nohd_m > reach[t].nohd_m) reach[t] = rows[r * count + t];
    }
  return reach;
}

FarReach farReach(const FarField& field, double mpe_w_m2, double extinction_per_m) {
  return farReaches(field, std::span<const double>(&mpe_w_m2, 1), extinction_per_m).front();
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

FarField::Face::Face(const ObserverField& field, const Vec3& centre)
    : spec(field.spec()), stats(field.stats()), intensity_w_sr(field.irradianceLattice()) {
  const int n = stats.nodes[0];
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      float& e = intensity_w_sr[static_cast<std::size_t>(j) * static_cast<std::size_t>(n) +
                                static_cast<std::size_t>(i)];
      const Vec3 d = spec.position(i, j, 0) - centre;
      e = static_cast<float>(std::min(static_cast<double>(e) * glm::dot(d, d), kFloatMax));
    }
  for (const FieldBlock& b : field.blocks()) {
    if (b.status == VoxelStatus::Unresolved) unresolved.push_back(b);
    if (b.status == VoxelStatus::BelowFloor) continue;
    field::forEachSample(b.size, [&](int di, int dj, int) {
      const int i = b.origin[0] + di, j = b.origin[1] + dj;
      if (i < n && j < n) integrated.push_back(static_cast<std::uint32_t>(j * n + i));
    });
  }
  std::sort(integrated.begin(), integrated.end());
  integrated.erase(std::unique(integrated.begin(), integrated.end()), integrated.end());
}

FarField::FarField(LitBall ball, FarFieldSpec spec, double map_distance_m, std::vector<Face> faces,
                   std::vector<Peak> located)
    : ball_(ball),
      spec_(spec),
      map_distance_m_(map_distance_m),
      faces_(std::move(faces)),
      located_(std::move(located)) {
  for (const Face& face : faces_) {
    FieldStats counts = face.stats.countsOnly();
    // In intensity: no point of a face is farther than √3 × the distance.
    counts.unconverged_max_upper_w_m2 =
        hazardSafe(counts.unconverged_max_upper_w_m2) * 3.0 * map_distance_m * map_distance_m;
    stats_ += counts;
  }
  lattice_peak_.intensity_w_sr = 0.0;
  forEachDirection([&](const Vec3& d, double intensity_w_sr) {
    if (hazardSafe(intensity_w_sr) > lattice_peak_.intensity_w_sr) {
      lattice_peak_ = {intensity_w_sr, d, Basis::Located};
    }
  });
  // A narrow glint's block bounds the irradiance in the ball about it, which holds the face's
  // square of the block: as intensity, times the farthest distance in the ball, squared.
  for (int f = 0; f < kFaces; ++f) {
    const Face& face = faces_[static_cast<std::size_t>(f)];
    for (const FieldBlock& b : face.unresolved) {
      const Vec3 centre =
          face.spec.position(b.origin[0] + b.size[0] / 2, b.origin[1] + b.size[1] / 2, 0);
      const double radius_m = 0.5 * std::hypot(b.size[0], b.size[1]) * face.spec.voxel_m;
      const double reach_m = glm::length(centre - ball_.centre_m) + radius_m;
      narrow_glints_.push_back({hazardSafe(b.bound_w_m2) * reach_m * reach_m,
                                glm::normalize(centre - ball_.centre_m), Basis::NarrowGlintBound});
      auto& index = narrow_index_[static_cast<std::size_t>(f)];
      index.emplace_back(narrowKey(b.origin[0] / 2, b.origin[1] / 2, spec_.face_pixels),
                         narrow_glints_.back().intensity_w_sr);
    }
    auto& index = narrow_index_[static_cast<std::size_t>(f)];
    std::sort(index.begin(), index.end());
  }
  const int n = spec_.face_pixels;
  const int tiles = (n + kTile - 1) / kTile;
  for (int f = 0; f < kFaces; ++f) {
    std::vector<float>& tile = tile_max_[static_cast<std::size_t>(f)];
    tile.assign(static_cast<std::size_t>(tiles) * static_cast<std::size_t>(tiles), 0.0f);
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const auto e = static_cast<float>(hazardSafe(latticeIntensity(f, i, j)));
        if (!(e > 0.0f)) continue;
        // Every tile within two lattice points of (i, j) reads it.
        for (int b = std::max(0, (j - 2) / kTile); b <= std::min(tiles - 1, (j + 2) / kTile); ++b)
          for (int a = std::max(0, (i - 2) / kTile); a <= std::min(tiles - 1, (i + 2) / kTile);
               ++a) {
            float& t = tile[static_cast<std::size_t>(b) * static_cast<std::size_t>(tiles) +
                            static_cast<std::size_t>(a)];
            t = std::max(t, e);
          }
      }
  }
  std::stable_sort(located_.begin(), located_.end(), [](const Peak& a, const Peak& b) {
    return a.intensity_w_sr > b.intensity_w_sr;
  });
  peak_ = lattice_peak_;
  for (const std::vector<Peak>* list : {&located_, &narrow_glints_}) {
    for (const Peak& p : *list) {
      if (hazardSafe(p.intensity_w_sr) > peak_.intensity_w_sr) peak_ = p;
    }
  }
  // Nothing was found above the floor: the floor is all the map knows of the peak.
  if (peak_.intensity_w_sr < spec_.floor_w_sr)
    peak_ = {spec_.floor_w_sr, peak_.direction, Basis::Floor};
  prepareHazardWindow();
}

const char* FarField::basisName(Basis b) {
  switch (b) {
    case Basis::Located:
      return "located";
    case Basis::NarrowGlintBound:
      return "narrow_glint_bound";
    case Basis::Floor:
      return "floor";
  }
  return "located";
}

Vec3 FarField::latticeDirection(int face, int i, int j) const {
  return planeDirection(face, i, j, spec_.face_pixels);
}

double FarField::intensity(const Vec3& direction) const {
  const FaceHit h = faceHit(direction, spec_.face_pixels);
  return bilinear(h.face, cellOf(h.x), cellOf(h.y), h.x, h.y);
}

int FarField::cellOf(double x) const {
  return std::clamp(static_cast<int>(std::floor(x)), 0, spec_.face_pixels - 1);
}

double FarField::bilinear(int face, int i, int j, double x, double y) const {
  const double fx = x - i, fy = y - j;
  return (1.0 - fy) *
             ((1.0 - fx) * latticeIntensity(face, i, j) + fx * latticeIntensity(face, i + 1, j)) +
         fy * ((1.0 - fx) * latticeIntensity(face, i, j + 1) +
               fx * latticeIntensity(face, i + 1, j + 1));
}

// Bilinear interpolation of a concave stretch errs by at most h²/8 × |f''| per axis, and f''
// h² is about the lattice's second difference there. About a lobe's top that difference
// averages f'' over ±h and reads low: for a Gaussian of width w sampled at h ≤ w, at worst
// 0.56 of h² f''(top) (samples at ±h/2 about the top). Doubled, it covers that: the allowance
// is (the largest concave second difference at the cell's corners along x, plus along y) / 4.
double FarField::cellAllowance(int face, int i, int j) const {
  const int n = spec_.face_pixels;
  double corners_max = 0.0;
  for (int c = 0; c < 4; ++c)
    corners_max = std::max(corners_max, latticeIntensity(face, i + (c & 1), j + (c >> 1)));
  if (!(corners_max > 0.0)) return std::isnan(corners_max) ? corners_max : 0.0;  // dark
  double along_x = 0.0, along_y = 0.0;
  for (int c = 0; c < 4; ++c) {
    const int a = i + (c & 1), b = j + (c >> 1);
    // On the face's edge, the difference one step in.
    const int ax = std::clamp(a, 1, n - 1), by = std::clamp(b, 1, n - 1);
    along_x =
        std::max(along_x, 2.0 * latticeIntensity(face, ax, b) - latticeIntensity(face, ax - 1, b) -
                              latticeIntensity(face, ax + 1, b));
    along_y =
        std::max(along_y, 2.0 * latticeIntensity(face, a, by) - latticeIntensity(face, a, by - 1) -
                              latticeIntensity(face, a, by + 1));
  }
  return 0.25 * (along_x + along_y);
}

double FarField::narrowGlintBoundAt(int face, double x, double y) const {
  const auto& index = narrow_index_[static_cast<std::size_t>(face)];
  if (index.empty()) return 0.0;
  // Finest blocks are 2 × 2 lattice cells at even origins; a point on their edge lies in both.
  double bound = 0.0;
  const auto blocksAlong = [](double c, int out[2]) {
    const double k = std::floor(0.5 * c);
    out[0] = static_cast<int>(k);
    out[1] = 0.5 * c == k ? out[0] - 1 : out[0];
  };
  int bx[2], by[2];
  blocksAlong(x, bx);
  blocksAlong(y, by);
  for (const int a : bx)
    for (const int b : by) {
      if (a < 0 || b < 0) continue;
      const std::uint64_t key = narrowKey(a, b, spec_.face_pixels);
      const auto it =
          std::lower_bound(index.begin(), index.end(), std::make_pair(key, 0.0),
                           [](const auto& l, const auto& r) { return l.first < r.first; });
      if (it != index.end() && it->first == key) bound = std::max(bound, it->second);
    }
  return bound;
}

double FarField::tileBrightest(int face, int i0, int j0, int i1, int j1) const {
  const int tiles = (spec_.face_pixels + kTile - 1) / kTile;
  const std::vector<float>& tile = tile_max_[static_cast<std::size_t>(face)];
  double brightest = 0.0;
  for (int b = std::max(0, j0 / kTile); b <= std::min(tiles - 1, std::max(0, j1) / kTile); ++b)
    for (int a = std::max(0, i0 / kTile); a <= std::min(tiles - 1, std::max(0, i1) / kTile); ++a) {
      brightest = std::max(
          brightest,
          static_cast<double>(tile[static_cast<std::size_t>(b) * static_cast<std::size_t>(tiles) +
                                   static_cast<std::size_t>(a)]));
    }
  return brightest;
}

bool FarField::dark(int face, int i0, int j0, int i1, int j1) const {
  if (!narrow_index_[static_cast<std::size_t>(face)].empty()) return false;
  const int tiles = (spec_.face_pixels + kTile - 1) / kTile;
  const std::vector<float>& tile = tile_max_[static_cast<std::size_t>(face)];
  for (int b = std::max(0, j0 / kTile); b <= std::min(tiles - 1, j1 / kTile); ++b)
    for (int a = std::max(0, i0 / kTile); a <= std::min(tiles - 1, i1 / kTile); ++a) {
      if (tile[static_cast<std::size_t>(b) * static_cast<std::size_t>(tiles) +
               static_cast<std::size_t>(a)] != 0.0f) {
        return false;
      }
    }
  return true;
}

double FarField::upperIntensityAt(int face, double x, double y) const {
  const int i = cellOf(x), j = cellOf(y);
  if (dark(face, i, j, i, j)) return 0.0;
  const double upper = std::max(bilinear(face, i, j, x, y) + cellAllowance(face, i, j),
                                narrowGlintBoundAt(face, x, y));
  return std::min(hazardSafe(upper), peak_.intensity_w_sr);
}

double FarField::brightestWithin(int face, int i, int j, int steps) const {
  const int n = spec_.face_pixels;
  double brightest = 0.0;
  for (int y = std::max(0, j - steps); y <= std::min(n, j + steps); ++y)
    for (int x = std::max(0, i - steps); x <= std::min(n, i + steps); ++x)
      brightest = std::max(brightest, hazardSafe(latticeIntensity(face, x, y)));
  return brightest;
}

namespace {

// out[k] = the largest of in[k − s .. k + s] (clipped to 0 .. count − 1), elements @p stride
// apart in both: a running maximum that keeps the window's falling sequence of candidates.
void runningMaximum(const float* in, float* out, int count, std::size_t stride, int s,
                    std::vector<int>& candidates) {
  candidates.clear();
  std::size_t front = 0;
  int next = 0;  // the first element not yet taken in
  for (int k = 0; k < count; ++k) {
    for (; next <= std::min(count - 1, k + s); ++next) {
      const float v = in[static_cast<std::size_t>(next) * stride];
      while (candidates.size() > front &&
             !(in[static_cast<std::size_t>(candidates.back()) * stride] > v)) {
        candidates.pop_back();
      }
      candidates.push_back(next);
    }
    while (candidates[front] < k - s) ++front;
    out[static_cast<std::size_t>(k) * stride] =
        in[static_cast<std::size_t>(candidates[front]) * stride];
  }
}

}  // namespace

FarField::BrightestWindow::BrightestWindow(const FarField& map, int steps)
    : steps_(std::max(0, steps)), row_(static_cast<std::size_t>(map.spec().face_pixels) + 1) {
  const int count = static_cast<int>(row_);
  const std::size_t points = row_ * row_;
  std::vector<float> along_rows(points);
  std::vector<int> candidates;
  for (int f = 0; f < kFaces; ++f) {
    // What brightestWithin() compares: NaN as +∞, nothing below 0.
    std::vector<float>& out = brightest_[static_cast<std::size_t>(f)];
    out.resize(points);
    for (std::size_t p = 0; p < points; ++p) {
      out[p] = static_cast<float>(
          std::max(0.0, hazardSafe(static_cast<double>(
                            map.faces_[static_cast<std::size_t>(f)].intensity_w_sr[p]))));
    }
    for (int j = 0; j < count; ++j) {
      const std::size_t first = static_cast<std::size_t>(j) * row_;
      runningMaximum(&out[first], &along_rows[first], count, 1, steps_, candidates);
    }
    for (int i = 0; i < count; ++i) {
      runningMaximum(&along_rows[static_cast<std::size_t>(i)], &out[static_cast<std::size_t>(i)],
                     count, row_, steps_, candidates);
    }
  }
}

std::uint64_t FarField::BrightestWindow::bytes(int face_pixels) {
  const auto row = static_cast<std::uint64_t>(face_pixels) + 1;
  // The six faces' maxima and one face's pass along the rows.
  return (kFaces + 1) * row * row * sizeof(float);
}

int FarField::hazardSteps(double far_m) const {
  const int n = spec_.face_pixels;
  const double parallax_rad = ball_.radius_m / std::max(far_m - ball_.radius_m, 1e-300);
  return std::min(kFarRadiusReferenceSteps,
                  static_cast<int>(std::min(parallax_rad * n / 2.0, static_cast<double>(n))) + 1) +
         1;
}

void FarField::prepareHazardWindow() {
  hazard_window_.reset();
  if (!spec_.far_radius_verified) return;
  hazard_window_ = std::make_shared<const BrightestWindow>(*this, hazardSteps(spec_.far_radius_m));
}

double FarField::latticeUpperIntensity(int face, int i, int j) const {
  const int n = spec_.face_pixels;
  if (dark(face, std::max(0, i - 1), std::max(0, j - 1), std::min(i, n - 1), std::min(j, n - 1))) {
    return 0.0;
  }
  double allowance = 0.0;
  for (int c = 0; c < 4; ++c) {
    const int a = i - 1 + (c & 1), b = j - 1 + (c >> 1);
    if (a < 0 || b < 0 || a >= n || b >= n) continue;
    allowance = std::max(allowance, hazardSafe(cellAllowance(face, a, b)));
  }
  const double upper =
      std::max(latticeIntensity(face, i, j) + allowance, narrowGlintBoundAt(face, i, j));
  return std::min(hazardSafe(upper), peak_.intensity_w_sr);
}

double FarField::upperIntensityAlong(const Vec3& a, const Vec3& b) const {
  return upperIntensityAlong(a, b, 0);
}

// Exact for the estimate: on a face the arc is a straight segment, and between the lattice
// lines it crosses it runs in one lattice cell, where the estimate is bilinear plus a
// constant: quadratic along it, largest at an end or, where it bends down, at its vertex.
double FarField::upperIntensityAlong(const Vec3& a, const Vec3& b, int depth) const {
  const int n = spec_.face_pixels;
  const FaceHit ha = faceHit(a, n), hb = faceHit(b, n);
  if (ha.face != hb.face && depth < 4) {
    // Split where the arc leaves a's face; the two sides meet within 2^-40 of the arc.
    double lo = 0.0, hi = 1.0;
    for (int k = 0; k < 40; ++k) {
      const double mid = 0.5 * (lo + hi);
      (faceHit(glm::normalize(a + mid * (b - a)), n).face == ha.face ? lo : hi) = mid;
    }
    return std::max(upperIntensityAlong(a, glm::normalize(a + lo * (b - a)), depth + 1),
                    upperIntensityAlong(glm::normalize(a + hi * (b - a)), b, depth + 1));
  }
  if (ha.face != hb.face) return std::max(upperIntensity(a), upperIntensity(b));
  const int face = ha.face;
  const int last = n - 1;
  if (dark(face, std::clamp(static_cast<int>(std::min(ha.x, hb.x)), 0, last),
           std::clamp(static_cast<int>(std::min(ha.y, hb.y)), 0, last),
           std::clamp(static_cast<int>(std::max(ha.x, hb.x)), 0, last),
           std::clamp(static_cast<int>(std::max(ha.y, hb.y)), 0, last))) {
    return 0.0;
  }
  const double dx = hb.x - ha.x, dy = hb.y - ha.y;
  // The parameters where the segment crosses a lattice line, ends included.
  thread_local std::vector<double> cuts;
  cuts.assign(1, 0.0);
  const auto crossings = [&](double from, double step) {
    if (step == 0.0) return;
    const double to = from + step;
    for (double k = std::floor(std::min(from, to)) + 1.0; k < std::max(from, to); k += 1.0) {
      cuts.push_back((k - from) / step);
    }
  };
  crossings(ha.x, dx);
  crossings(ha.y, dy);
  cuts.push_back(1.0);
  std::sort(cuts.begin(), cuts.end());
  const auto count = cuts.size();
  // Points on a lattice line are put exactly on it, so that the cell test sees both sides.
  const auto at = [&](double t) {
    double x = ha.x + t * dx, y = ha.y + t * dy;
    if (std::abs(x - std::round(x)) < 1e-9) x = std::round(x);
    if (std::abs(y - std::round(y)) < 1e-9) y = std::round(y);
    return PlanePoint{x, y};
  };
  double best = 0.0;
  for (std::size_t c = 0; c < count; ++c) {
    const PlanePoint p = at(cuts[c]);
    best = std::max(best, upperIntensityAt(face, p.x, p.y));
    if (c + 1 == count || !(cuts[c + 1] > cuts[c])) continue;
    // The bilinear value along the piece to the next cut is e0 + e1 s + e2 s², s ∈ 0 .. 1.
    const PlanePoint q = at(cuts[c + 1]);
    const int i = cellOf(0.5 * (p.x + q.x)), j = cellOf(0.5 * (p.y + q.y));
    const double f00 = latticeIntensity(face, i, j), f10 = latticeIntensity(face, i + 1, j);
    const double f01 = latticeIntensity(face, i, j + 1);
    const double f11 = latticeIntensity(face, i + 1, j + 1);
    const double twist = f11 - f10 - f01 + f00;
    const double u0 = p.x - i, v0 = p.y - j, du = q.x - p.x, dv = q.y - p.y;
    const double e2 = twist * du * dv;
    if (!(e2 < 0.0)) continue;  // no interior top
    const double e1 = (f10 - f00) * du + (f01 - f00) * dv + twist * (u0 * dv + v0 * du);
    const double s = -e1 / (2.0 * e2);
    if (s > 0.0 && s < 1.0) {
      best = std::max(best, upperIntensityAt(face, p.x + s * du, p.y + s * dv));
    }
  }
  return best;
}

double FarField::upperIntensity(const Vec3& direction) const {
  const FaceHit h = faceHit(direction, spec_.face_pixels);
  return upperIntensityAt(h.face, h.x, h.y);
}

double FarField::hazardDistanceToward(const Vec3& direction, double upper_w_sr,
                                      double threshold_w_m2, double extinction_per_m) const {
  return hazardDistance(hazardIntensityToward(direction, upper_w_sr), threshold_w_m2,
                        extinction_per_m, ball_.radius_m);
}

double FarField::hazardIntensityToward(const Vec3& direction, double upper_w_sr) const {
  const double upper = hazardSafe(upper_w_sr);
  if (!std::isfinite(upper)) return std::numeric_limits<double>::infinity();
  // The brightest lattice direction in the parallax cone at the far radius (where the cone is
  // widest), as the check sought it, one step wider for a direction between lattice points.
  const int n = spec_.face_pixels;
  const int steps = hazardSteps(farRadiusToward(spec_, direction));
  const FaceHit h = faceHit(direction, n);
  const int i = static_cast<int>(std::lround(h.x)), j = static_cast<int>(std::lround(h.y));
  // The tiles' maxima bound the square's from above: where that is no more than the upper
  // estimate itself (the dark sky, above all), the lattice is not read point by point.
  double brightest = upper;
  if (tileBrightest(h.face, i - steps, j - steps, i + steps, j + steps) > upper) {
    const double within = hazard_window_ && hazard_window_->steps() == steps
                              ? hazard_window_->at(h.face, i, j)
                              : brightestWithin(h.face, i, j, steps);
    brightest = std::max(upper, within);
  }
  // E r² ≤ I + share × (tolerance × max(brightest, threshold × r²) + floor): the threshold is
  // reached either where the brightest term rules or where its own share does.
  const double share = 1.0 + kFarRadiusReadShare;
  const double tolerance = share * spec_.tolerance;
  const double floor_w_sr = share * spec_.floor_w_sr;
  const double by_brightest = upper + floor_w_sr + tolerance * brightest;
  const double by_threshold = (upper + floor_w_sr) / std::max(1.0 - tolerance, 1e-300);
  return std::max(by_brightest, by_threshold);
}

namespace {

// The search for lobe tops (locateLobeTops()): how many lobes, how far apart their starts
// must be (in lattice spacings), how many integrations each may take, and how finely it
// closes in (a 64th of the lattice spacing: the top's rise over the rest is below 1e-4 for a
// lobe as wide as the lattice, and the last parabolas bound it).
constexpr std::size_t kMaxLobes = 8;
constexpr double kLobesApart = 4.0;
constexpr int kMaxProbes = 64;
constexpr double kFinestStep = 1.0 / 64.0;
// The integrator's tolerance in the search, as a share of the map's: the top's intensity is
// reported, so it is integrated far more closely than the map's lattice.
constexpr double kSearchToleranceShare = 1e-2;

// The intensity toward a direction with its error estimate (W/sr).
struct Probe {
  Vec3 direction{1.0, 0.0, 0.0};
  double intensity_w_sr = 0.0;
  double error_w_sr = 0.0;
};

// The offset of the top of the parabola through (−h, lo), (0, mid), (h, hi), within ±h (the
// larger end where it bends up or is flat), in log I where all three are positive (where a
// Gaussian lobe is a parabola); and how much higher than mid, relatively, a top within h/2 of
// mid may rise on that parabola: |second difference| / 8.
struct Step {
  double offset = 0.0;
  double rise = 0.0;
};
Step parabolaStep(double lo, double mid, double hi, double h) {
  const bool logs = lo > 0.0 && mid > 0.0 && hi > 0.0;
  if (logs) {
    lo = std::log(lo);
    mid = std::log(mid);
    hi = std::log(hi);
  }
  const double bend = lo + hi - 2.0 * mid;
  if (!std::isfinite(bend)) return {};
  if (!(bend < 0.0)) return {hi > lo ? h : lo > hi ? -h : 0.0, 0.0};
  const double rise = logs ? std::expm1(-0.125 * bend) : mid > 0.0 ? -0.125 * bend / mid : 0.0;
  return {std::clamp(0.5 * h * (lo - hi) / bend, -h, h), rise};
}

// A lattice direction where a lobe's top may be near.
struct LobeStart {
  double intensity_w_sr;
  int face, i, j;
};

// The lattice directions at least as bright as their neighbours on the face and half the
// @p brightest, brightest first, at most kMaxLobes and none within kLobesApart lattice angles
// of a brighter one.
std::vector<LobeStart> lobeStarts(const FarField& map, double brightest) {
  const int n = map.spec().face_pixels;
  std::vector<LobeStart> starts;
  for (int f = 0; f < FarField::kFaces; ++f) {
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double v = map.latticeIntensity(f, i, j);
        if (!(v >= 0.5 * brightest)) continue;
        bool top = true;
        for (int dj = -1; dj <= 1 && top; ++dj)
          for (int di = -1; di <= 1 && top; ++di) {
            const int a = i + di, b = j + dj;
            if (a < 0 || b < 0 || a > n || b > n) continue;
            top = !(map.latticeIntensity(f, a, b) > v);
          }
        if (top) starts.push_back({v, f, i, j});
      }
  }
  std::stable_sort(starts.begin(), starts.end(), [](const LobeStart& a, const LobeStart& b) {
    return a.intensity_w_sr > b.intensity_w_sr;
  });
  std::vector<LobeStart> chosen;
  for (const LobeStart& s : starts) {
    if (chosen.size() == kMaxLobes) break;
    const Vec3 d = map.latticeDirection(s.face, s.i, s.j);
    const double apart_rad = kLobesApart * latticeAngle(s.i, s.j, n);
    const bool near = std::any_of(chosen.begin(), chosen.end(), [&](const LobeStart& c) {
      return glm::dot(d, map.latticeDirection(c.face, c.i, c.j)) > std::cos(apart_rad);
    });
    if (!near) chosen.push_back(s);
  }
  return chosen;
}

}  // namespace

std::vector<FarField::Peak> locateLobeTops(const FarField& map, const FacetIntegrator& integrator,
                                           std::int64_t* evaluations) {
  const int n = map.spec().face_pixels;
  const double brightest = map.latticePeak().intensity_w_sr;
  if (!(brightest > 0.0) || !std::isfinite(brightest)) return {};
  const std::vector<LobeStart> chosen = lobeStarts(map, brightest);

  const double distance_m = map.mapDistance();
  const Vec3 centre = map.ball().centre_m;
  const double d2 = distance_m * distance_m;
  const FacetIntegrator search =
      integrator
          .withAccuracy(kSearchToleranceShare * map.spec().tolerance,
                        kSearchToleranceShare * map.spec().floor_w_sr / d2)
          .withReturnExtinction(0.0);
  std::vector<FarField::Peak> tops(chosen.size());
  std::vector<std::int64_t> spent(chosen.size(), 0);
  tbb::enumerable_thread_specific<IntegratorWorkspace> workspaces;
  tbb::parallel_for(std::size_t{0}, chosen.size(), [&](std::size_t k) {
    IntegratorWorkspace& ws = workspaces.local();
    int probes = 0;
    const auto probe = [&](const Vec3& d) {
      const ObserverResult r = search.adaptive(centre + distance_m * d, ws);
      ++probes;
      spent[k] += r.evaluations;
      return Probe{d, r.irradiance_w_m2 * d2, r.error_estimate_w_m2 * d2};
    };
    const LobeStart& s = chosen[k];
    Probe best = probe(map.latticeDirection(s.face, s.i, s.j));
    const Vec3 e1 = glm::normalize(glm::cross(
        best.direction, std::abs(best.direction.z) < 0.9 ? Vec3(0, 0, 1) : Vec3(1, 0, 0)));
    const Vec3 e2 = glm::cross(best.direction, e1);
    const double h0 = latticeAngle(s.i, s.j, n);
    double h = h0;
    std::array<double, 2> rise{0.0, 0.0};
    while (h > kFinestStep * h0 && probes + 5 <= kMaxProbes) {
      const Vec3 at = best.direction;
      const std::array<Probe, 4> around = {
          probe(glm::normalize(at - h * e1)), probe(glm::normalize(at + h * e1)),
          probe(glm::normalize(at - h * e2)), probe(glm::normalize(at + h * e2))};
      const Step s1 =
          parabolaStep(around[0].intensity_w_sr, best.intensity_w_sr, around[1].intensity_w_sr, h);
      const Step s2 =
          parabolaStep(around[2].intensity_w_sr, best.intensity_w_sr, around[3].intensity_w_sr, h);
      rise = {s1.rise, s2.rise};
      Probe next = best;
      for (const Probe& p : around) {
        if (p.intensity_w_sr > next.intensity_w_sr) next = p;
      }
      if (s1.offset != 0.0 || s2.offset != 0.0) {
        const Probe p = probe(glm::normalize(at + s1.offset * e1 + s2.offset * e2));
        if (p.intensity_w_sr > next.intensity_w_sr) next = p;
      }
      // The top lies within this stencil: look closer.
      if (glm::length(next.direction - at) < 0.5 * h) h *= 0.5;
      best = next;
    }
    // The top may rise above the best probe by what the last parabolas allow within half
    // their step.
    tops[k] = {(best.intensity_w_sr + best.error_w_sr) * (1.0 + rise[0]) * (1.0 + rise[1]),
               best.direction, FarField::Basis::Located};
  });
  if (evaluations != nullptr) {
    for (const std::int64_t e : spent) *evaluations += e;
  }
  return tops;
}

std::uint64_t farFieldMemoryFloorBytes(const FarFieldSpec& spec, std::uint64_t after_faces_bytes) {
  const double directions = (spec.face_pixels + 1.0) * (spec.face_pixels + 1.0);
  // The faces are computed one at a time; their planes differ only in where they lie.
  const double face =
      static_cast<double>(fieldMemoryFloorBytes(cubeFaceSpec(0, Vec3(0.0), 1.0, spec), false));
  // After the faces, the brightest direction in each one's parallax square (BrightestWindow:
  // as many bytes again, held by the far radius's check and then by the map) stays beside
  // the writers' scratch.
  const double window = static_cast<double>(FarField::BrightestWindow::bytes(spec.face_pixels));
  const double bytes = FarField::kFaces * directions * sizeof(float) +
                       std::max(face, window + static_cast<double>(after_faces_bytes));
  return bytes >= 1.8e19 ? std::numeric_limits<std::uint64_t>::max()
                         : static_cast<std::uint64_t>(bytes);
}

std::uint64_t latLongMapBytes(int height, int face_pixels) {
  const double face = (face_pixels + 1.0) * (face_pixels + 1.0);
  return static_cast<std::uint64_t>(3.0 * sizeof(double) * 2.0 * height * height +
                                    (sizeof(std::uint32_t) + sizeof(double)) * face);
}

FarField computeFarField(const FacetIntegrator& integrator, const FarFieldSpec& spec,
                         WorkCounter* counter, PointExchange* exchange) {
  validate(spec);
  const LitBall ball = litBall(integrator);
  const double distance_m = kMapDistanceInFarRadii * spec.far_radius_m;
  std::vector<FarField::Face> faces;
  faces.reserve(FarField::kFaces);
  for (int f = 0; f < FarField::kFaces; ++f) {
    if (counter != nullptr) counter->beginStage("face", f + 1, FarField::kFaces);
    const FieldSpec face = cubeFaceSpec(f, ball.centre_m, distance_m, spec);
    // A quarter of the map's tolerance and floor, as for every observer field
    // (fieldIntegratorOptions()). Intensity is read unattenuated along the reflected paths:
    // the air's share is the hazard distance's (hazardDistance()).
    const FacetIntegrator at_face =
        integrator.withAccuracy(0.25 * face.tolerance, 0.25 * face.floor_w_m2)
            .withReturnExtinction(0.0);
    // Each face's grids are dropped as soon as its lattice is taken.
    faces.emplace_back(computeField(at_face, face, ExcludedFn(), counter, exchange), ball.centre_m);
  }
  // The lattice alone, to find where the lobes' tops are; then the map that reports them.
  FarField lattice(ball, spec, distance_m, std::move(faces));
  std::int64_t search_evaluations = 0;
  std::vector<FarField::Peak> tops = locateLobeTops(lattice, integrator, &search_evaluations);
  FarField far(ball, spec, distance_m, std::move(lattice.faces_), std::move(tops));
  far.stats_.evaluations += search_evaluations;
  if (counter != nullptr) counter->endStages();
  far.radius_check_ = verifyFarRadius(far, integrator, counter, exchange);
  if (far.radius_check_.radius_m > 0.0) {
    far.spec_.far_radius_m = far.radius_check_.radius_m;
    far.spec_.far_radius_verified = true;
    far.prepareHazardWindow();
  }
  return far;
}

LatLongIntensity latLongIntensity(const FarField& field, int height) {
  LatLongIntensity m;
  m.height = height;
  m.width = 2 * height;
  const auto w = static_cast<std::size_t>(m.width);
  const auto h = static_cast<std::size_t>(height);
  std::vector<double> cos_az(w + 1), sin_az(w + 1), cos_el(h + 1), sin_el(h + 1);
  for (std::size_t i = 0; i <= w; ++i) {
    const double azimuth = -kPi + static_cast<double>(i) * 2.0 * kPi / m.width;
    cos_az[i] = std::cos(azimuth);
    sin_az[i] = std::sin(azimuth);
  }
  for (std::size_t j = 0; j <= h; ++j) {
    const double elevation = -0.5 * kPi + static_cast<double>(j) * kPi / height;
    cos_el[j] = std::cos(elevation);
    sin_el[j] = std::sin(elevation);
  }
  const auto corner = [&](std::size_t i, std::size_t j) {
    return Vec3(cos_el[j] * cos_az[i], cos_el[j] * sin_az[i], sin_el[j]);
  };
  // The cells' edges: along each parallel j (0 .. height) from meridian i to i + 1, and along
  // each meridian i from parallel j to j + 1; each shared by the two cells beside it.
  std::vector<double> along_parallel((h + 1) * w), along_meridian(h * w);
  tbb::parallel_for(std::size_t{0}, h + 1, [&](std::size_t j) {
    for (std::size_t i = 0; i < w; ++i) {
      along_parallel[j * w + i] = field.upperIntensityAlong(corner(i, j), corner(i + 1, j));
      if (j < h)
        along_meridian[j * w + i] = field.upperIntensityAlong(corner(i, j), corner(i, j + 1));
    }
  });
  std::vector<double>& cell = m.upper_w_sr;
  cell.assign(w * h, 0.0);
  tbb::parallel_for(std::size_t{0}, h, [&](std::size_t j) {
    for (std::size_t i = 0; i < w; ++i) {
      cell[j * w + i] = std::max({along_parallel[j * w + i], along_parallel[(j + 1) * w + i],
                                  along_meridian[j * w + i], along_meridian[j * w + (i + 1) % w]});
    }
  });
  // Inside a cell, the estimate is largest at a lattice direction or a located top.
  const auto pixelOf = [&](const Vec3& d) {
    const double azimuth = std::atan2(d.y, d.x);
    const double elevation = std::asin(std::clamp(d.z, -1.0, 1.0));
    const int i =
        std::clamp(static_cast<int>((azimuth + kPi) / (2.0 * kPi) * m.width), 0, m.width - 1);
    const int j =
        std::clamp(static_cast<int>((elevation + 0.5 * kPi) / kPi * height), 0, height - 1);
    return static_cast<std::uint32_t>(static_cast<std::size_t>(j) * w +
                                      static_cast<std::size_t>(i));
  };
  // A face's lattice directions, their pixels and upper intensities found in parallel, then
  // taken into the cells in order (a face's worth of scratch, not a lock per pixel).
  const int n = field.spec().face_pixels;
  const auto row = static_cast<std::size_t>(n) + 1;
  std::vector<std::uint32_t> pixel(row * row);
  std::vector<double> upper(row * row);
  for (int f = 0; f < FarField::kFaces; ++f) {
    tbb::parallel_for(0, n + 1, [&](int j) {
      for (int i = 0; i <= n; ++i) {
        const std::size_t k = static_cast<std::size_t>(j) * row + static_cast<std::size_t>(i);
        upper[k] = field.latticeUpperIntensity(f, i, j);
        if (upper[k] > 0.0) pixel[k] = pixelOf(field.latticeDirection(f, i, j));
      }
    });
    for (std::size_t k = 0; k < row * row; ++k) {
      if (!(upper[k] > 0.0)) continue;
      double& c = cell[pixel[k]];
      c = std::max(c, upper[k]);
    }
  }
  for (const FarField::Peak& top : field.located()) {
    double& c = cell[pixelOf(top.direction)];
    c = std::max(c, std::min(hazardSafe(top.intensity_w_sr), field.peak().intensity_w_sr));
  }
  return m;
}

std::vector<float> latLongHazardDistance(const FarField& field, const LatLongIntensity& map,
                                         double threshold_w_m2, double extinction_per_m) {
  std::vector<float> distance_m(map.upper_w_sr.size());
  tbb::parallel_for(std::size_t{0}, distance_m.size(), [&](std::size_t p) {
    // The hazard distance toward the pixel where it lies beyond the far radius there, else 0.
    const Vec3 d = latLongDirection(p, map.width, map.height);
    const double nohd =
        field.hazardDistanceToward(d, map.upper_w_sr[p], threshold_w_m2, extinction_per_m);
    distance_m[p] = nohd >= farRadiusToward(field.spec(), d)
                        ? static_cast<float>(std::min(nohd, kFloatMax))
                        : 0.0f;
  });
  return distance_m;
}

LatLongMap latLongMap(const FarField& field, int height, double mpe_w_m2, double extinction_per_m,
                      double aided_mpe_w_m2) {
  const LatLongIntensity cells = latLongIntensity(field, height);
  LatLongMap m;
  m.width = cells.width;
  m.height = cells.height;
  m.intensity_w_sr.resize(cells.upper_w_sr.size());
  for (std::size_t p = 0; p < cells.upper_w_sr.size(); ++p) {
    m.intensity_w_sr[p] = static_cast<float>(std::min(cells.upper_w_sr[p], kFloatMax));
  }
  m.nohd_m = latLongHazardDistance(field, cells, mpe_w_m2, extinction_per_m);
  if (aided_mpe_w_m2 > 0.0) {
    m.aided_nohd_m = latLongHazardDistance(field, cells, aided_mpe_w_m2, extinction_per_m);
  }
  return m;
}

namespace {

// The largest upper intensity in each vertex's cell of a cube-sphere of m² cells a face: from
// the cells' edges, then the lattice directions and located tops inside them (those beyond a
// face's edges too). Per face, [b × (m + 1) + a].
std::vector<std::vector<double>> vertexUpperIntensities(const FarField& field, int m) {
  const int n = field.spec().face_pixels;
  const int step = n / m;  // both powers of two
  const double half_cell = 0.5 * step;
  const auto row = static_cast<std::size_t>(m + 1);
  const auto vertices = row * row;
  // The vertices (a, b) of a face whose cell, |x − a step| ≤ step/2 and likewise for y (its
  // plane's lattice units, beyond the face's edges too), holds plane point (x, y).
  const auto forEachVertexHolding = [&](double x, double y, auto&& fn) {
    // A direction nearly in the face's plane lands far out on it: clamped before the cast to
    // int, which would overflow (and is undefined) beyond the vertex range anyway.
    const auto range = [&](double c, int& lo, int& hi) {
      const auto vertex = [&](double at) { return std::clamp(at / step, -1.0, m + 1.0); };
      lo = std::max(0, static_cast<int>(std::ceil(vertex(c - half_cell))));
      hi = std::min(m, static_cast<int>(std::floor(vertex(c + half_cell))));
    };
    int a0, a1, b0, b1;
    range(x, a0, a1);
    range(y, b0, b1);
    for (int b = b0; b <= b1; ++b)
      for (int a = a0; a <= a1; ++a)
        fn(static_cast<std::size_t>(b) * row + static_cast<std::size_t>(a));
  };
  std::vector<std::vector<double>> vertex_max(FarField::kFaces);
  tbb::parallel_for(0, FarField::kFaces, [&](int f) {
    std::vector<double>& v = vertex_max[static_cast<std::size_t>(f)];
    v.assign(vertices, 0.0);
    for (int b = 0; b <= m; ++b)
      for (int a = 0; a <= m; ++a) {
        const double x0 = a * step - half_cell, x1 = a * step + half_cell;
        const double y0 = b * step - half_cell, y1 = b * step + half_cell;
        const Vec3 c00 = planeDirection(f, x0, y0, n), c10 = planeDirection(f, x1, y0, n);
        const Vec3 c01 = planeDirection(f, x0, y1, n), c11 = planeDirection(f, x1, y1, n);
        v[static_cast<std::size_t>(b) * row + static_cast<std::size_t>(a)] =
            std::max({field.upperIntensityAlong(c00, c10), field.upperIntensityAlong(c10, c11),
                      field.upperIntensityAlong(c11, c01), field.upperIntensityAlong(c01, c00)});
      }
    const auto lend = [&](const Vec3& d, double intensity_w_sr) {
      if (!(glm::dot(d, kFaceFrames[static_cast<std::size_t>(f)].normal) > 0.0)) return;
      const PlanePoint p = onFacePlane(d, f, n);
      forEachVertexHolding(p.x, p.y, [&](std::size_t k) { v[k] = std::max(v[k], intensity_w_sr); });
    };
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) {
        const double upper = field.latticeUpperIntensity(f, i, j);
        if (upper > 0.0) {
          forEachVertexHolding(i, j, [&](std::size_t k) { v[k] = std::max(v[k], upper); });
        }
      }
    // Another face's directions reach this face's cells only within half a cell (and a
    // lattice step of slack) of their shared edge.
    const int margin = static_cast<int>(half_cell) + 2;
    for (int g = 0; g < FarField::kFaces; ++g) {
      if (g == f) continue;
      for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i) {
          if (i > margin && i < n - margin && j > margin && j < n - margin) {
            i = n - margin - 1;  // skip the face's inside
            continue;
          }
          const double upper = field.latticeUpperIntensity(g, i, j);
          if (upper > 0.0) lend(field.latticeDirection(g, i, j), upper);
        }
    }
    for (const FarField::Peak& top : field.located()) {
      lend(top.direction, std::min(hazardSafe(top.intensity_w_sr), field.peak().intensity_w_sr));
    }
  });

  return vertex_max;
}

}  // namespace

HazardSurface hazardSurface(const FarField& field, int cells_per_face, double mpe_w_m2,
                            double extinction_per_m) {
  const int n = field.spec().face_pixels;
  const int m = std::clamp(cells_per_face, 1, n);
  const int step = n / m;
  const auto row = static_cast<std::size_t>(m + 1);
  const std::vector<std::vector<double>> vertex_max = vertexUpperIntensities(field, m);
  HazardSurface s;
  const Vec3 centre = field.ball().centre_m;
  for (int f = 0; f < FarField::kFaces; ++f) {
    const FarField::Face& face = field.faces()[static_cast<std::size_t>(f)];
    const std::vector<double>& vertex = vertex_max[static_cast<std::size_t>(f)];
    const auto first = static_cast<std::int64_t>(s.points_m.size());
    for (int b = 0; b <= m; ++b)
      for (int a = 0; a <= m; ++a) {
        const Vec3 p = face.spec.position(a * step, b * step, 0);
        const Vec3 dir = glm::normalize(p - centre);
        const double intensity =
            vertex[static_cast<std::size_t>(b) * row + static_cast<std::size_t>(a)];
        const double nohd = field.hazardDistanceToward(dir, intensity, mpe_w_m2, extinction_per_m);
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
