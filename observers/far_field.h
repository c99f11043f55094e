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
///
/// What the map reports fails safe: each bright lobe's top is located between the lattice
/// directions by a search with the integrator, a lobe narrower than the lattice is reported by
/// its bound, and the maps hold for each cell an upper estimate of the intensity anywhere in it
/// (upperIntensity()).

#include <array>
#include <cstdint>
#include <limits>
#include <memory>
#include <span>
#include <utility>
#include <vector>

#include "facets/integrator.h"
#include "facets/lit_ball.h"
#include "observers/field.h"

namespace glint {

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
  int block_pixels = 64;    ///< coarsest block edge (a power of two ≤ face_pixels)
  double tolerance = 1e-2;  ///< of the map's interpolation, and of I/r² beyond far_radius_m
  double floor_w_sr = 0.0;  ///< intensity below this counts as negligible
  /// The lowest irradiance that is hazardous (W/m²: the MPE, or the aided MPE if lower; 0:
  /// none given). The far radius check holds E r² to I(ω) within the tolerance × the larger of
  /// the brightest intensity the parallax reaches and this × r²: an error in a direction too
  /// dim to be hazardous at r that is a small share of the hazard there changes no verdict.
  double hazard_threshold_w_m2 = 0.0;
  double far_radius_m = 0.0;  ///< farRadius() away from the forward cone: the smallest
  double lit_radius_m = 0.0;  ///< of the LitBall (for farRadiusToward())
  /// The narrowest width of the target's directional terms (Target::narrowestWidthRad(): a
  /// lobe's σ, ABg's peak, a table's step); ∞ when nothing reflects but diffusely.
  double narrowest_sigma = std::numeric_limits<double>::infinity();
  Vec3 beam_direction{1.0, 0.0, 0.0};  ///< unit propagation direction of the laser
  int bound_split_depth = 2;  ///< FieldSpec::bound_split_depth of the faces: shallow, since
  /// every block of a face sees the whole target under a tiny angle and deep pieces only
  /// multiply its candidate list (cylinder, σ = 0.003: 1.1 GB at depth 2, over 8 GB at 6)
  /// The innermost sphere verifyFarRadius() may bring the far radius in to (m); 0: no check,
  /// the first-order rule stands. The floor must be proven negligible there: a direction below
  /// it has been computed by nobody, so the far field cannot speak for it any nearer.
  double innermost_far_radius_m = 0.0;
  /// Set by computeFarField(): far_radius_m was verified by direct integration and holds in
  /// every direction, the forward cone included (farRadiusToward()).
  bool far_radius_verified = false;
  double first_order_far_radius_m = 0.0;  ///< farRadius() away from the forward cone
};

/// @brief verifyFarRadius() reads E r² with the integrator at this share of its allowance: the
/// far field's guarantee carries that reading error besides the tolerance.
inline constexpr double kFarRadiusReadShare = 0.1;
/// @brief verifyFarRadius() seeks the parallax cone's brightest direction within this many
/// lattice steps (a smaller square can only lower it, so the check only gets stricter).
inline constexpr int kFarRadiusReferenceSteps = 32;

/// @brief The far radius toward unit @p direction: the verified radius (FarRadiusCheck) where
/// the map has one, else farRadius() at the direction's angle from the beam.
double farRadiusToward(const FarFieldSpec& spec, const Vec3& direction);

/// @brief The far radius brought in from the first-order rule by checking it: on spheres about
/// the lit centre, from the first-order radius inward by halves down to
/// FarFieldSpec::innermost_far_radius_m, the near field is integrated directly toward every
/// direction the map integrated (its blocks' samples, FarField::Face::integrated) and the
/// lobe tops it located, and each E r² is compared with I(ω).
///
/// The first-order rule (farRadius()) bounds each lit point's contribution on its own; in the
/// sum the symmetric part of the parallax cancels, and what is left falls as the light's
/// virtual source (where the rays toward ω appear to come from) and its spread allow: a
/// mirror sphere's virtual source lies half its radius behind the surface, a cylinder's glint
/// line spreads only along its axis. Those are what E r² − I(ω) measures, so the check measures
/// them rather than bounding them term by term.
///
/// A sphere holds where, at every direction checked, |E r² − I(ω)| ≤ tolerance × the larger of
/// the brightest lattice intensity within the parallax angle a / (r − a) of ω (sought within
/// 32 lattice steps, which can only tighten it) and the lowest hazardous irradiance × r², plus
/// the floor; E r² is read at a tenth of the tolerance. The far radius is the innermost sphere
/// of the unbroken run that holds from the first inward, settled to a factor √2 by one more
/// sphere between the last that held and the first that failed. Between the spheres it read,
/// the check relies on E r² − I(ω), a series in 1/r once it is this small, not rising again
/// with r. If the first sphere fails, radius_m is 0 and the first-order rule stands. With
/// @p exchange the directions are dealt out and every process gets the same answer.
struct FarRadiusCheck {
  struct Sphere {
    double radius_m = 0.0;
    /// The largest |E r² − I(ω)| over the allowance above: at most 1 where the sphere holds.
    double worst_share = 0.0;
    Vec3 worst_direction{1.0, 0.0, 0.0};
    bool holds = false;
  };
  std::vector<Sphere> spheres;  ///< outside in
  double radius_m = 0.0;
  std::int64_t directions = 0;  ///< checked on each sphere
  std::int64_t evaluations = 0;
  double seconds = 0.0;
};

/// @brief The computed map of radiant intensity over all directions.
class FarField {
 public:
  /// @brief Cube faces in the order +x, −x, +y, −y, +z, −z.
  static constexpr int kFaces = 6;

  /// @brief A computed cube face, kept as its lattice of intensity: a face's OpenVDB grids
  /// hold a one-voxel layer in 8³ leaves (and level and status beside it), 20× the 4 bytes a
  /// direction needs (the 2 km example: 470 MB against 25 MB).
  struct Face {
    FieldSpec spec;
    FieldStats stats;
    /// The irradiance computed at each lattice point × its distance² from the centre (W/sr):
    /// (face_pixels + 1)², row j at j (face_pixels + 1).
    std::vector<float> intensity_w_sr;
    /// The finest blocks where a glint narrower than the lattice may pass between the
    /// directions (VoxelStatus::Unresolved, with their bound).
    std::vector<FieldBlock> unresolved;
    /// The lattice points integrated (the samples of every block not proven below the floor),
    /// as j (face_pixels + 1) + i, ascending: where verifyFarRadius() reads the near field.
    std::vector<std::uint32_t> integrated;
    /// @brief An empty face whose lattice is set by hand (a map built without integration).
    Face() = default;
    /// @brief From the face's field, the cube's centre at @p centre.
    Face(const ObserverField& field, const Vec3& centre);
  };

  /// @brief Where a reported intensity comes from.
  enum class Basis : std::uint8_t {
    /// Computed: the largest intensity a search with the integrator found about a lobe's top
    /// (plus its error estimate), or a lattice direction's.
    Located,
    /// A bound: a glint narrower than the lattice may pass between the directions of a face
    /// block, and no located lobe is brighter than the block's bound.
    NarrowGlintBound,
    /// A bound: no direction was found above the floor, which bounds them all.
    Floor,
  };

  /// @brief The basis's name in the outputs: `located`, `narrow_glint_bound` or `floor`.
  static const char* basisName(Basis b);

  /// @brief A direction of the map and the intensity there.
  struct Peak {
    double intensity_w_sr = 0.0;
    Vec3 direction{1.0, 0.0, 0.0};
    Basis basis = Basis::Located;
  };

  /// @brief The map from its faces; @p located: lobe tops found between the lattice
  /// directions (locateLobeTops()).
  FarField(LitBall ball, FarFieldSpec spec, double map_distance_m, std::vector<Face> faces,
           std::vector<Peak> located = {});

  [[nodiscard]] const LitBall& ball() const { return ball_; }
  [[nodiscard]] const FarFieldSpec& spec() const { return spec_; }
  /// @brief Distance from the centre of the cube faces on which the map was integrated.
  [[nodiscard]] double mapDistance() const { return map_distance_m_; }
  /// @brief The faces: irradiance at mapDistance(), as computed (with their statistics).
  [[nodiscard]] const std::vector<Face>& faces() const { return faces_; }

  /// @brief I(ω) in W/sr for unit @p direction, bilinear between the map's lattice points.
  [[nodiscard]] double intensity(const Vec3& direction) const;

  /// @brief What the map says the intensity toward unit @p direction may be at most: the
  /// bilinear value plus the error bilinear interpolation makes where the lattice bends down
  /// (h²/8 × the curvature per axis, which the lattice's second differences, doubled,
  /// overestimate for a lobe at least as wide as the lattice), the bound of a narrow glint's
  /// block where there is one, and never more than peak().
  [[nodiscard]] double upperIntensity(const Vec3& direction) const;

  /// @brief The peak intensity the map reports, never below the truth: the brightest located
  /// lobe top, or the bound of a narrow glint's block or of the floor where that is higher.
  [[nodiscard]] const Peak& peak() const { return peak_; }
  /// @brief The brightest lattice direction (below the true peak where a lobe's top falls
  /// between the directions).
  [[nodiscard]] const Peak& latticePeak() const { return lattice_peak_; }
  /// @brief The lobe tops located between the lattice directions, the brightest first.
  [[nodiscard]] const std::vector<Peak>& located() const { return located_; }
  /// @brief Each face block where a glint narrower than the lattice may pass: its bound as an
  /// intensity toward the block's centre (basis NarrowGlintBound; +∞ where it has none).
  [[nodiscard]] const std::vector<Peak>& narrowGlints() const { return narrow_glints_; }

  /// @brief How the far radius was verified (empty spheres where it was not).
  [[nodiscard]] const FarRadiusCheck& farRadiusCheck() const { return radius_check_; }

  /// @brief Sums of the faces' statistics (lattice points, evaluations, time); the
  /// unconverged points' largest irradiance plus error is given as an intensity (W/sr).
  [[nodiscard]] const FieldStats& stats() const { return stats_; }

  /// @brief Calls fn(i, j, direction, intensity_w_sr) for every lattice point (i, j) of cube
  /// face @p face.
  template <class Fn>
  void forEachDirectionOfFace(int face, Fn&& fn) const {
    const int n = spec_.face_pixels + 1;
    for (int j = 0; j < n; ++j)
      for (int i = 0; i < n; ++i)
        fn(i, j, latticeDirection(face, i, j), latticeIntensity(face, i, j));
  }

  /// @brief Calls fn(direction, intensity_w_sr) for every lattice point of every face.
  template <class Fn>
  void forEachDirection(Fn&& fn) const {
    for (int f = 0; f < kFaces; ++f) {
      forEachDirectionOfFace(f, [&](int, int, const Vec3& d, double i_w_sr) { fn(d, i_w_sr); });
    }
  }

  /// @brief The unit direction of lattice point (@p i, @p j) of cube face @p face.
  [[nodiscard]] Vec3 latticeDirection(int face, int i, int j) const;
  /// @brief Its intensity as computed (W/sr).
  [[nodiscard]] double latticeIntensity(int face, int i, int j) const {
    const auto row = static_cast<std::size_t>(spec_.face_pixels) + 1;
    return static_cast<double>(
        faces_[static_cast<std::size_t>(face)]
            .intensity_w_sr[static_cast<std::size_t>(j) * row + static_cast<std::size_t>(i)]);
  }
  /// @brief The largest lattice intensity within @p steps lattice points of (i, j) along
  /// either axis on face @p face (the square clipped to the face), W/sr.
  [[nodiscard]] double brightestWithin(int face, int i, int j, int steps) const;

  /// @brief brightestWithin() for one @p steps at every lattice point at once: two running
  /// maxima per face (along rows, then columns), O(directions) to build, one read a query.
  /// The far field's readers ask it at every direction (the hazard reach, the maps, the far
  /// radius's check), where a scan of the (2 steps + 1)² square each would cost them minutes.
  class BrightestWindow {
   public:
    BrightestWindow(const FarField& map, int steps);
    [[nodiscard]] int steps() const { return steps_; }
    /// @brief brightestWithin(face, i, j, steps()), exactly (W/sr).
    [[nodiscard]] double at(int face, int i, int j) const {
      return static_cast<double>(brightest_[static_cast<std::size_t>(
          face)][static_cast<std::size_t>(j) * row_ + static_cast<std::size_t>(i)]);
    }
    /// @brief What one holds for a map of @p face_pixels (bytes).
    static std::uint64_t bytes(int face_pixels);

   private:
    int steps_ = 0;
    std::size_t row_ = 0;
    std::array<std::vector<float>, kFaces> brightest_;
  };
  /// @brief upperIntensity() at lattice point (i, j): its own intensity plus the largest
  /// interpolation allowance of the lattice cells around it, capped as upperIntensity() is.
  [[nodiscard]] double latticeUpperIntensity(int face, int i, int j) const;
  /// @brief The largest upperIntensity() along the great-circle arc from unit @p a to unit
  /// @p b (a map cell's edge: short).
  [[nodiscard]] double upperIntensityAlong(const Vec3& a, const Vec3& b) const;

  /// @brief The hazard distance toward unit @p direction, whose intensity the map puts at
  /// most at @p upper_w_sr, for @p threshold_w_m2 through air of @p extinction_per_m: the
  /// distance beyond which E ≤ threshold wherever the far field speaks.
  ///
  /// Beyond the far radius E r² is I(ω) only to within the tolerance × the larger of the
  /// brightest lattice direction in the parallax cone (as verifyFarRadius() seeks it) and
  /// threshold × r², plus the floor, and the check read E r² to a tenth of that besides. A
  /// near apparent source (a convex mirror's virtual image) sits in that allowance: with E r²
  /// up to I + allowance, E falls to the threshold only at √((I + allowance) / threshold), about
  /// half the tolerance farther than √(I / threshold). 0 where the allowance is 0 too; +∞ for
  /// a non-finite intensity.
  [[nodiscard]] double hazardDistanceToward(const Vec3& direction, double upper_w_sr,
                                            double threshold_w_m2, double extinction_per_m) const;
  /// @brief The intensity hazardDistanceToward() judges toward unit @p direction, whatever the
  /// threshold: @p upper_w_sr and its allowance (W/sr; +∞ for a non-finite intensity).
  [[nodiscard]] double hazardIntensityToward(const Vec3& direction, double upper_w_sr) const;

 private:
  friend FarField computeFarField(const FacetIntegrator&, const FarFieldSpec&, WorkCounter*,
                                  PointExchange*);
  // The lattice cell (along one axis) that holds face coordinate x (lattice units).
  [[nodiscard]] int cellOf(double x) const;
  // The bilinear intensity at (x, y) of a face, in lattice cell (i, j).
  [[nodiscard]] double bilinear(int face, int i, int j, double x, double y) const;
  // upperIntensity() at face coordinates (x, y) of a face, in lattice units (0 .. face_pixels).
  [[nodiscard]] double upperIntensityAt(int face, double x, double y) const;
  // upperIntensityAlong() of an arc that @p depth splits at face edges have made.
  [[nodiscard]] double upperIntensityAlong(const Vec3& a, const Vec3& b, int depth) const;
  // Whether upperIntensity() is 0 throughout lattice cells (i0 .. i1, j0 .. j1) of a face (cell
  // (i, j) spans lattice points i .. i + 1, j .. j + 1): every intensity their estimate reads
  // is 0 and the face has no narrow glint. False may be answered for a dark region, never
  // true for a lit one.
  [[nodiscard]] bool dark(int face, int i0, int j0, int i1, int j1) const;
  // At least the largest lattice intensity of points (i0 .. i1, j0 .. j1) of a face (clipped to
  // it): the largest of the tiles that hold them.
  [[nodiscard]] double tileBrightest(int face, int i0, int j0, int i1, int j1) const;
  // The square's half-width (lattice steps) hazardDistanceToward() reads the brightest
  // direction in, toward a direction whose far radius is @p far_m.
  [[nodiscard]] int hazardSteps(double far_m) const;
  // Once the far radius is verified (one radius, so one half-width for every direction), the
  // window hazardDistanceToward() reads.
  void prepareHazardWindow();
  // The interpolation allowance of lattice cell (i, j) .. (i + 1, j + 1) of a face.
  [[nodiscard]] double cellAllowance(int face, int i, int j) const;
  // The largest bound of a narrow glint's block whose closed square holds (x, y); 0 if none.
  [[nodiscard]] double narrowGlintBoundAt(int face, double x, double y) const;

  LitBall ball_;
  FarFieldSpec spec_;
  FarRadiusCheck radius_check_;
  double map_distance_m_ = 0.0;
  std::vector<Face> faces_;
  FieldStats stats_;
  Peak peak_;
  Peak lattice_peak_;
  std::vector<Peak> located_;
  std::vector<Peak> narrow_glints_;
  // Per face: the narrow glints' blocks (2 × 2 lattice cells at even origins) by their
  // origin's key, sorted, with their intensity bound.
  std::array<std::vector<std::pair<std::uint64_t, double>>, kFaces> narrow_index_;
  // Per face: the largest lattice intensity of each tile of kTile × kTile cells and of the two
  // lattice points around it (what the cells' estimates read), row-major by tile.
  static constexpr int kTile = 8;
  std::array<std::vector<float>, kFaces> tile_max_;
  std::shared_ptr<const BrightestWindow> hazard_window_;  // (null before the radius is verified)
};

/// @brief Locates the top of each bright lobe of @p map between its lattice directions: from
/// each lattice direction at least as bright as its eight neighbours and half the brightest
/// (the brightest few, apart), a pattern search with parabolic steps on log I(ω), I read at
/// the map's distance with @p integrator at a hundredth of the map's tolerance, down to a
/// 64th of the lattice spacing. Each top is reported as I plus its error estimate plus the
/// rise the last parabolas allow within half their step: not below the lobe's true top.
/// @p evaluations, if given, is increased by the reflection calculations spent.
std::vector<FarField::Peak> locateLobeTops(const FarField& map, const FacetIntegrator& integrator,
                                           std::int64_t* evaluations = nullptr);

/// @brief The lattice of cube face @p face (FarField order) at @p distance_m from @p centre_m,
/// as an observer plane: axes u, v, u × v = the face's outward normal.
FieldSpec cubeFaceSpec(int face, const Vec3& centre_m, double distance_m, const FarFieldSpec& spec);

/// @brief A floor under the memory computeFarField() takes for @p spec (bytes), known before
/// anything is allocated: the six faces' lattices of intensity, 4 bytes a direction, all kept,
/// and the field of the face being computed (fieldMemoryFloorBytes() of its plane: the grids'
/// leaves, 64 bytes a direction), or, once the last face's field is gone, the brightest
/// direction about each (FarField::BrightestWindow, 4⅔ bytes a direction) and
/// @p after_faces_bytes (the writers' scratch: latLongMapBytes() and its channels), where that
/// is more.
/// Measured (glint run, a dark far field, peak resident memory less the run without it; MB =
/// 2²⁰ bytes): 1 549 MB at face_pixels 4096 (this: 1 412 MB), 487 MB at 2048 (354 MB); one
/// face's grids at 4096, 1 174 MB (1 028 MB); the lat-long map at height 2048, 192 to 224 MB
/// (latLongMapBytes(): 192 MB).
std::uint64_t farFieldMemoryFloorBytes(const FarFieldSpec& spec,
                                       std::uint64_t after_faces_bytes = 0);

/// @brief What latLongIntensity() of @p height holds while it is made, for a map of
/// @p face_pixels (bytes): the upper intensities along both edges of every cell and the cells'
/// own, three doubles a pixel, and a face's lattice directions' pixels and upper intensities.
std::uint64_t latLongMapBytes(int height, int face_pixels);

/// @brief Checks the far radius of @p map with @p integrator (see FarRadiusCheck).
FarRadiusCheck verifyFarRadius(const FarField& map, const FacetIntegrator& integrator,
                               WorkCounter* counter = nullptr, PointExchange* exchange = nullptr);

/// @brief Computes the map: each cube face as an adaptive observer plane at a thousand far
/// radii (where the map's own parallax is a thousandth of its tolerance), with @p integrator
/// at that plane's accuracy; then, where the spec names an innermost radius, the far radius is
/// verified inward (verifyFarRadius(); FarField::farRadiusCheck()). @p counter and @p exchange
/// as for computeField().
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
/// toward +z. Each pixel holds the largest upperIntensity() over its cell: along its edges
/// (where they cross lattice lines, and where the interpolant bends down between) and at
/// the lattice directions and located lobe tops inside it, so no glint narrower than a pixel
/// is lost and none is cut short. Arrays are indexed [j × width + i].
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

/// @brief What a LatLongMap's pixels hold before any threshold: the largest upperIntensity()
/// over each cell (W/sr, [j × width + i]), found once for the maps of every threshold.
struct LatLongIntensity {
  int width = 0;
  int height = 0;
  std::vector<double> upper_w_sr;
};
LatLongIntensity latLongIntensity(const FarField& field, int height);

/// @brief LatLongMap::nohd_m of @p map's pixels for @p threshold_w_m2: hazardDistanceToward()
/// where it is at least the far radius toward the pixel's centre, else 0 (m).
std::vector<float> latLongHazardDistance(const FarField& field, const LatLongIntensity& map,
                                         double threshold_w_m2, double extinction_per_m);

/// @brief The hazard boundary as a closed surface about the lit centre: a cube-sphere of
/// cells_per_face² quads per face, each vertex at the distance √(I/MPE) of its direction where
/// that is beyond the far radius toward it, else at that far radius (where the box decides).
/// A vertex takes the largest upperIntensity() of its cell (the square of half a cell's
/// width about it, on its face and beyond its edges), as a pixel of latLongMap() does.
struct HazardSurface {
  std::vector<Vec3> points_m;
  std::vector<std::array<std::int64_t, 4>> quads;
  std::vector<float> nohd_m;                    ///< per point; 0 where the hazard ends inside r_far
  std::vector<float> intensity_w_sr;            ///< per point
  std::vector<std::uint8_t> beyond_far_radius;  ///< per point: 1 where nohd_m ≥ r_far
};
HazardSurface hazardSurface(const FarField& field, int cells_per_face, double mpe_w_m2,
                            double extinction_per_m = 0.0);

/// @brief The farthest hazard the far field proves: the largest hazard distance
/// (FarField::hazardDistanceToward()) where it is at least the far radius toward its direction,
/// over the located lobe tops, the narrow glints' bounds and the lattice directions'
/// upperIntensity() (0 and the map's peak direction where there is none).
struct FarReach {
  double nohd_m = 0.0;
  Vec3 direction{1.0, 0.0, 0.0};
  double far_radius_m = 0.0;  ///< toward that direction
};
FarReach farReach(const FarField& field, double mpe_w_m2, double extinction_per_m = 0.0);
/// @brief farReach() for each of @p thresholds_w_m2, in their order, in one pass over the map.
std::vector<FarReach> farReaches(const FarField& field, std::span<const double> thresholds_w_m2,
                                 double extinction_per_m = 0.0);

}  // namespace glint
