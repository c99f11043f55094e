#pragma once
/// @file
/// @brief The far field by direction: the radiant intensity I(ω) the target sends in each
/// direction, on an adaptive cube map, and the hazard distance it implies per direction.
///
/// Beyond a far radius r_far from the lit facets the irradiance is E(c + r ω) = I(ω)/r² within
/// the map's accuracy, so one map of directions stands for every observer out to any range:
/// the nominal ocular hazard distance of the reflection in direction ω is √(I(ω)/MPE) wherever
/// that is beyond r_far (nearer, the observer box decides).
///
/// Each cube face is an observer plane (observers/field.h) at a distance far beyond r_far, so
/// the map is refined, bounded and interpolated by the same block check as the box: a glint
/// narrower than its samples is found by bound, never interpolated away.

#include <array>
#include <cstdint>
#include <limits>
#include <vector>

#include "facets/integrator.h"
#include "observers/field.h"

namespace glint {

/// @brief The ball around the lit facets: the far field's origin and size.
struct LitBall {
  /// The centre of the lit facets' corners' bounding box (the adaptive field's centre of
  /// spread too, FieldBuilder): distances and directions of the far field are taken from here.
  Vec3 centre_m{0.0};
  double radius_m = 0.0;  ///< holds every lit curved patch (their bounding balls)
};

/// @brief The ball of @p integrator's lit facets; radius 0 when nothing is lit.
LitBall litBall(const FacetIntegrator& integrator);

/// @brief The far radius: beyond it, E(c + r ω) r² differs from I(ω) by at most @p tolerance ×
/// the intensity of the brightest direction the parallax can reach (first order in a/r).
///
/// Two effects separate an observer at distance r from the far field, a = @p lit_radius_m:
///  - its distance from each lit point is r ± a, so 1/d² differs from 1/r² by ≤ 2a/(r − a);
///  - it sees each lit point in a direction up to a/(r − a) off ω. A point's radiance varies
///    with its outgoing direction no faster than the specular lobe: the Beckmann factor
///    exp(−tan²θh/σ²) changes by at most √2 e^{-1/2}/σ ≈ 0.86/σ of its peak per radian of the
///    half vector, which turns by 1/(2 cos θd) radian per radian of the outgoing direction
///    (θd: half the angle between the directions toward the laser and the observer), so by
///    0.43/(σ cos θd) in all; the Lambertian part by ≤ 1 per radian. Every feature of I(ω), a
///    beam footprint's edge or a rim included, is a sum of such lobes, so none is sharper.
/// cos θd = sin(ψ/2), ψ the angle of ω from the beam's own direction: the rate is at most 1/σ
/// beyond ψ = 51°, and grows as 0.43/(σ sin(ψ/2)) into the forward cone, where the half vector
/// of a grazing reflection is ill-defined and the far radius grows without bound.
/// Hence the relative error is ≤ (a/(r − a)) (3 + g(ψ)/σ_min) with g = max(1, 0.43/sin(ψ/2)),
/// and r_far = a (1 + (3 + g(ψ)/σ_min) / tolerance). The bound is first order: a target
/// symmetric about its light's centroid (a cylinder lit whole) cancels that order and is far
/// better than promised. @p narrowest_sigma is the smallest σ of a material with a specular
/// part (∞ when none); @p forward_angle_rad is ψ (default: away from the forward cone).
double farRadius(double lit_radius_m, double narrowest_sigma, double tolerance,
                 double forward_angle_rad = 3.14159265358979323846);

/// @brief What the far field is computed for (scene key `far_field`).
struct FarFieldSpec {
  /// Lattice intervals along a cube face's edge, a power of two: directions are sampled 2/N
  /// rad apart at a face's centre (N = 1024: 0.11°), closer toward its edges.
  int face_pixels = 1024;
  int block_pixels = 64;      ///< coarsest block edge (a power of two ≤ face_pixels)
  double tolerance = 1e-2;    ///< of the map's interpolation, and of I/r² beyond far_radius_m
  double floor_w_sr = 0.0;    ///< intensity below this counts as negligible
  double far_radius_m = 0.0;  ///< farRadius() away from the forward cone: the smallest
  double lit_radius_m = 0.0;  ///< of the LitBall (for farRadiusToward())
  double narrowest_sigma =
      std::numeric_limits<double>::infinity();  ///< smallest specular σ of the target's materials
  Vec3 beam_direction{1.0, 0.0, 0.0};           ///< unit propagation direction of the laser
  int bound_split_depth = 2;  ///< FieldSpec::bound_split_depth of the faces: shallow, since
  /// every block of a face sees the whole target under a tiny angle and deep pieces only
  /// multiply its candidate list (cylinder, σ = 0.003: 1.1 GB at depth 2, over 8 GB at 6)
};

/// @brief The far radius toward unit @p direction: farRadius() at its angle from the beam.
double farRadiusToward(const FarFieldSpec& spec, const Vec3& direction);

/// @brief The computed map of radiant intensity over all directions.
class FarField {
 public:
  /// @brief Cube faces in the order +x, −x, +y, −y, +z, −z.
  static constexpr int kFaces = 6;

  /// @brief A computed cube face, kept as its lattice of irradiance: a face's OpenVDB grids
  /// hold a one-voxel layer in 8³ leaves (and level and status beside it), 20× the 4 bytes a
  /// direction needs (the 2 km example: 470 MB against 25 MB).
  struct Face {
    FieldSpec spec;
    FieldStats stats;
    std::vector<float> irradiance_w_m2;  ///< (face_pixels + 1)², row j at j (face_pixels + 1)
    explicit Face(const ObserverField& field);
  };

  FarField(LitBall ball, FarFieldSpec spec, double map_distance_m, std::vector<Face> faces);

  [[nodiscard]] const LitBall& ball() const { return ball_; }
  [[nodiscard]] const FarFieldSpec& spec() const { return spec_; }
  /// @brief Distance from the centre of the cube faces on which the map was integrated.
  [[nodiscard]] double mapDistance() const { return map_distance_m_; }
  /// @brief The faces: irradiance at mapDistance(), as computed (with their statistics).
  [[nodiscard]] const std::vector<Face>& faces() const { return faces_; }

  /// @brief I(ω) in W/sr for unit @p direction, bilinear between the map's lattice points.
  [[nodiscard]] double intensity(const Vec3& direction) const;

  /// @brief A direction of the map and the intensity there.
  struct Peak {
    double intensity_w_sr = 0.0;
    Vec3 direction{1.0, 0.0, 0.0};
  };
  /// @brief The brightest lattice direction of the map.
  [[nodiscard]] const Peak& peak() const { return peak_; }

  /// @brief Sums of the faces' statistics (lattice points, evaluations, time); the
  /// unconverged points' largest irradiance plus error is given as an intensity (W/sr).
  [[nodiscard]] const FieldStats& stats() const { return stats_; }

  /// @brief Calls fn(i, j, direction, intensity_w_sr) for every lattice point (i, j) of cube
  /// face @p face.
  template <class Fn>
  void forEachDirectionOfFace(int face, Fn&& fn) const {
    const std::vector<float>& e = faces_[static_cast<std::size_t>(face)].irradiance_w_m2;
    const int n = spec_.face_pixels + 1;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i) {
        const Vec3 p = latticePoint(face, i, j);
        const double d = glm::length(p - ball_.centre_m);
        fn(i, j, (p - ball_.centre_m) / d,
           static_cast<double>(e[static_cast<std::size_t>(j) * static_cast<std::size_t>(n) +
                                 static_cast<std::size_t>(i)]) *
               d * d);
      }
  }

  /// @brief Calls fn(direction, intensity_w_sr) for every lattice point of every face.
  template <class Fn>
  void forEachDirection(Fn&& fn) const {
    for (int f = 0; f < kFaces; ++f) {
      forEachDirectionOfFace(f, [&](int, int, const Vec3& d, double i_w_sr) { fn(d, i_w_sr); });
    }
  }

 private:
  [[nodiscard]] Vec3 latticePoint(int face, int i, int j) const;
  [[nodiscard]] double latticeIntensity(int face, int i, int j) const;

  LitBall ball_;
  FarFieldSpec spec_;
  double map_distance_m_ = 0.0;
  std::vector<Face> faces_;
  FieldStats stats_;
  Peak peak_;
};

/// @brief The lattice of cube face @p face (FarField order) at @p distance_m from @p centre_m,
/// as an observer plane: axes u, v, u × v = the face's outward normal.
FieldSpec cubeFaceSpec(int face, const Vec3& centre_m, double distance_m, const FarFieldSpec& spec);

/// @brief Computes the map: each cube face as an adaptive observer plane at a thousand far
/// radii (where the map's own parallax is a thousandth of its tolerance), with @p integrator
/// at that plane's accuracy. @p counter and @p exchange as for computeField().
/// @throw std::invalid_argument when @p spec is out of range; WorkStopped as computeField().
FarField computeFarField(const FacetIntegrator& integrator, const FarFieldSpec& spec,
                         WorkCounter* counter = nullptr, PointExchange* exchange = nullptr);

/// @brief The farthest distance r from a source of intensity @p intensity_w_sr at which
/// I T(r) / r² ≥ @p threshold_w_m2, with T(r) = exp(−μ max(0, r − @p source_radius_m)) the
/// transmission from the source's nearest point (so an upper bound): √(I / threshold) in vacuum.
/// 0 when I is 0; +∞ for a non-finite intensity (fail safe).
double hazardDistance(double intensity_w_sr, double threshold_w_m2, double extinction_per_m,
                      double source_radius_m);

/// @brief The hazard distance map in longitude and latitude: column i at azimuth
/// φ = −π + (i + ½) 2π/width from +x toward +y, row j at elevation −π/2 + (j + ½) π/height
/// toward +z. Each pixel holds the largest intensity of its cell: the value interpolated at
/// its centre or any lattice direction of the map inside it, so no glint narrower than a
/// pixel is lost. Arrays are indexed [j × width + i].
struct LatLongMap {
  int width = 0;
  int height = 0;
  std::vector<float> intensity_w_sr;
  /// hazardDistance(I, MPE, μ) where that is at least the far radius toward the pixel's centre; 0
  /// where the hazard, if any, ends nearer.
  std::vector<float> nohd_m;
  /// As nohd_m for the threshold @p aided_mpe_w_m2 (an optical aid's); empty without one.
  std::vector<float> aided_nohd_m;
};
LatLongMap latLongMap(const FarField& field, int height, double mpe_w_m2,
                      double extinction_per_m = 0.0, double aided_mpe_w_m2 = 0.0);

/// @brief The hazard boundary as a closed surface about the lit centre: a cube-sphere of
/// cells_per_face² quads per face, each vertex at the distance √(I/MPE) of its direction where
/// that is beyond the far radius toward it, else at that far radius (where the box decides).
/// A vertex takes the largest intensity of the map's lattice directions around it.
struct HazardSurface {
  std::vector<Vec3> points_m;
  std::vector<std::array<std::int64_t, 4>> quads;
  std::vector<float> nohd_m;                    ///< per point; 0 where the hazard ends inside r_far
  std::vector<float> intensity_w_sr;            ///< per point
  std::vector<std::uint8_t> beyond_far_radius;  ///< per point: 1 where nohd_m ≥ r_far
};
HazardSurface hazardSurface(const FarField& field, int cells_per_face, double mpe_w_m2,
                            double extinction_per_m = 0.0);

/// @brief The farthest hazard the far field proves: the largest √(I/MPE) over the map's
/// lattice directions where it is at least the far radius toward them (0 and the map's peak
/// direction where there is none).
struct FarReach {
  double nohd_m = 0.0;
  Vec3 direction{1.0, 0.0, 0.0};
  double far_radius_m = 0.0;  ///< toward that direction
};
FarReach farReach(const FarField& field, double mpe_w_m2, double extinction_per_m = 0.0);

}  // namespace glint
