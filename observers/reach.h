#pragma once
/// @file
/// @brief The hazard reach: how far the hazardous region extends in every direction from the
/// lit centre, from the target's surface out to infinity, without an observer box.
///
/// Two pieces close it. Out to the far radius, six radial lattices (RadialLattice, one per
/// cube face: rays from the lit centre, layers stepping evenly from a step off the centre to
/// the lit ball's radius and growing by a ratio beyond) are computed by the field's block
/// check, which skips by bound what cannot reach the threshold and marks Unresolved the
/// points between which a glint narrower than the lattice may pass. Only what lies inside
/// the target is left out (the shapes' own inside test, no margin). Beyond the far radius,
/// E(c + r ω) r² is I(ω) within the far field's tolerance, so the reach toward ω is the hazard
/// distance of the map's upper intensity there. A direction's reach is the larger of the two.
///
/// What it reports fails safe: a lattice point counts as hazardous at (1 − tolerance) × the
/// threshold, and so does an Unresolved one (and an Unconverged one where the largest value
/// plus error of those could reach it); the reach along a ray is the distance of the layer
/// beyond its farthest hazardous point; between rays the largest of the surrounding rays; beyond
/// the lattice the far field's hazard distance with its error allowance. The one region nothing
/// classifies is the cube of half-edge start_m about the lit centre inside the first layer
/// (two hundredths of the lit radius by default): the summary names it and counts it
/// hazardous in the volume, and the footprint counts its circumscribed ball.

#include <array>
#include <cstdint>
#include <vector>

#include "observers/field.h"

namespace glint {

class FarField;
struct FarReach;
struct LatLongIntensity;

/// @brief What the reach is computed for (scene key `reach`).
struct ReachSpec {
  Vec3 centre_m{0.0};  ///< the lit centre (LitBall)
  /// The lit ball's radius (m): beyond it the layers grow by ratio; inside it inner_layers
  /// layers step evenly from near_m / (inner_layers + 1), the first, to near_m.
  double near_m = 1.0;
  /// Layers inside the lit ball: a share 1 / (inner_layers + 1) of its radius apart, so that a
  /// point next to the lit surface counts hazardous within two such steps of it (a finest
  /// block whose ball reaches a lit facet counts hazardous whole).
  int inner_layers = 16;
  double far_m = 100.0;   ///< the last layer lies at least this far: the far radius (m)
  double ratio = 1.02;    ///< between layers: the reach's resolution along a ray
  int face_cells = 64;    ///< rays per cube-face edge (a multiple of block_voxels)
  int block_voxels = 16;  ///< coarsest block edge
  /// The thresholds the reach is given for (W/m²): the MPE, then the aided MPE if any, then
  /// each level's (HazardSpec::thresholdsW_m2()). The lattice is refined for the lowest.
  std::vector<double> thresholds_w_m2;
  double tolerance = 1e-2;
  double floor_w_m2 = 0.0;  ///< negligible irradiance (a thousandth of the lowest threshold)
};

/// @brief The radial lattice of cube face @p face (FarField order) for @p spec.
FieldSpec reachFaceSpec(int face, const ReachSpec& spec);

/// @brief The distance of the lattices' first layer from the centre (m): the half-edge of the
/// cube about the lit centre that no lattice point samples.
double reachStartM(const ReachSpec& spec);

/// @brief The radial lattices, read per ray: for ray (i, j) of a face, row j at j (face_cells
/// + 1), and each threshold t, the distance from the centre to the lattice point one layer
/// beyond the farthest hazardous one (0 where none is; the last layer's where that one is
/// hazardous, and the far field decides beyond it).
struct NearReach {
  struct Face {
    FieldSpec spec;
    FieldStats stats;
    std::vector<std::vector<float>> reach_m;  ///< [threshold][ray]
    /// [threshold][cell j × face_cells + i]: the farthest layer plane (m from the centre along
    /// the face's normal) one layer beyond a square of a layer between rays (i, j) and
    /// (i + 1, j + 1) that holds a point counted hazardous though its four rays are not there
    /// (see computeNearReach(): a peak as wide as the rays' spacing rising between them); 0
    /// where none does.
    std::vector<std::vector<float>> between_plane_m;
    std::vector<float> peak_w_m2;  ///< the largest irradiance along each ray
    /// Of stats' evaluated points and evaluations, those between the rays (not lattice points).
    std::int64_t between_points = 0;
    std::int64_t between_evaluations = 0;
  };
  ReachSpec spec;
  std::array<Face, 6> faces;
  /// Per threshold: the lattice's hazardous volume (each cell weighted by its hazardous
  /// corners' share), m³.
  std::vector<double> volume_m3;

  /// @brief The reach toward unit @p direction for threshold @p t, m: what the lattice says
  /// between its rays, the farthest layer plane of the four rays around it (the lattice cell
  /// that holds it) or of a square between them (Face::between_plane_m), taken along
  /// @p direction itself.
  [[nodiscard]] double toward(const Vec3& direction, std::size_t t) const;
  /// @brief The farthest layer plane (m from the centre along face @p face's normal) of the
  /// region hazardous for threshold @p t within lattice cell (i, j) of that face: its four rays'
  /// and its squares' between them (Face::between_plane_m).
  [[nodiscard]] double cellPlaneM(int face, std::size_t t, int i, int j) const;
  /// @brief The distance of the last layer along unit @p direction, m: the far field decides
  /// beyond it.
  [[nodiscard]] double lastLayerToward(const Vec3& direction) const;
  /// @brief Sums of the faces' statistics: lattice points evaluated, evaluations.
  [[nodiscard]] std::int64_t evaluatedPoints() const;
  [[nodiscard]] std::int64_t evaluations() const;
  [[nodiscard]] std::int64_t unresolvedPoints() const;
  /// @brief The points evaluated between the rays (of evaluatedPoints()).
  [[nodiscard]] std::int64_t betweenPoints() const;
};

/// @brief Computes the six radial lattices with @p integrator (@p counter, @p exchange as for
/// computeField()).
///
/// The field resolves its rays; between four rays of a layer it knows only their values. A
/// glint as wide as the rays' spacing may peak between them above every one (a lobe of σ 0.02
/// seen past rays 2.8° apart: 5 % of the reach lost), and one narrower than it is the field's
/// own narrow-glint bound's. So each square of four rays at each layer beyond what its rays
/// reach is judged by the largest value a peak of that width could have inside it: its rays'
/// largest plus an allowance for the concave second differences across the rays at its
/// corners. Where that reaches a threshold the square's centre and edge midpoints are
/// integrated and judged the same way with their own differences, then each quarter where
/// needed, down to a sixteenth of the spacing; it counts hazardous where a sample reaches the
/// threshold or, at the last halving, where the allowance still may. Every process of an MPI
/// job computes the same squares itself.
NearReach computeNearReach(const FacetIntegrator& integrator, const ReachSpec& spec,
                           const ExcludedFn& excluded, WorkCounter* counter = nullptr,
                           PointExchange* exchange = nullptr);

/// @brief What computeNearReach() holds beside each face's field (bytes): a face's points read
/// into a value and hazard bits, and what it keeps of all six (each threshold's reach per ray
/// and between the rays). fieldMemoryFloorBytes() of reachFaceSpec() counts the field itself.
std::uint64_t nearReachScratchBytes(const ReachSpec& spec);

/// @brief The reach for one threshold, from the lattices and the far field.
struct ReachSummary {
  double threshold_w_m2 = 0.0;
  /// The reach's largest distance from the lit centre over every direction, as toward() and
  /// the maps give it between the rays (m; 0: nothing hazardous
  /// outside the target but in the unclassified cube; +∞ where the far field has a glint it
  /// could not bound).
  double distance_m = 0.0;
  Vec3 direction{1.0, 0.0, 0.0};  ///< toward it
  Vec3 farthest_point_m{0.0};     ///< the lit centre + distance_m × direction (where finite)
  /// Every direction is proven: the lattice reached the far radius on every ray and the far
  /// field bounds every direction beyond it.
  bool closed = false;
  bool from_far_field = false;  ///< distance_m is the far field's (else the lattice's)
  /// The hazardous volume (m³): the lattice's, the unclassified cube's whole volume, and
  /// beyond the lattice the shell out to each far-field direction's hazard distance.
  double volume_m3 = 0.0;
  /// The cube about the lit centre inside the lattices' first layer, which no point samples:
  /// its half-edge (m) and volume (m³), counted hazardous in volume_m3 (the target's own inside,
  /// which it may hold, included: an over-statement of at most this volume).
  double unclassified_half_edge_m = 0.0;
  double unclassified_m3 = 0.0;
};

/// @brief The reach toward unit @p direction for threshold @p t: the lattice's (toward()) or,
/// beyond the far radius, the far field's hazard distance where that is farther (m).
double reachToward(const NearReach& near, const FarField& far, std::size_t t, const Vec3& direction,
                   double extinction_per_m);

/// @brief The reach for threshold @p t over every direction; @p beyond is the far field's
/// farReach() for that threshold and @p extinction_per_m (which the far field's hazard
/// distances have found already).
ReachSummary summarizeReach(const NearReach& near, const FarField& far, std::size_t t,
                            const FarReach& beyond, double extinction_per_m);

/// @brief The reach per direction on the map in longitude and latitude of @p beyond (the far
/// field's latLongIntensity(), LatLongMap's layout), for threshold @p t: reachToward() at each
/// pixel's centre, and the far field's largest hazard distance over the pixel (0 where nothing
/// along a direction is hazardous).
std::vector<float> reachLatLong(const NearReach& near, const FarField& far,
                                const LatLongIntensity& beyond, std::size_t t,
                                double extinction_per_m);

/// @brief The reach's boundary as a closed surface about the lit centre: per cube face a quad
/// mesh through the lattice's rays, each vertex at its ray's reach for threshold 0 (the far
/// field's hazard distance where that is farther), with the largest hazard ratio along the ray.
struct ReachSurface {
  std::vector<Vec3> points_m;
  std::vector<std::array<std::int64_t, 4>> quads;
  std::vector<float> distance_m;    ///< per point
  std::vector<float> hazard_ratio;  ///< per point: the ray's largest irradiance / threshold
};
ReachSurface reachSurface(const NearReach& near, const FarField& far, double extinction_per_m);

}  // namespace glint
