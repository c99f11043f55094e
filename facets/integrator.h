#pragma once
/// @file
/// @brief Irradiance at one observer from the whole target: the paper's adaptive 1→4 facet
/// refinement (Bailey et al. 2010, §2), made safe by bounds, and its uniform twin.

#include <cstdint>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "facets/beam.h"
#include "facets/patch.h"
#include "facets/reflection.h"
#include "facets/surface_map.h"
#include "facets/target.h"

namespace glint {

struct ShadowMesh;  // facets/occluder.h

/// @brief How each observer's integral over a lit facet is computed: each scheme is a rule (how a
/// piece is seeded, estimated and split) of the one refinement engine (detail/refine.h,
/// detail/schemes.h), chosen once per observer.
enum class IntegrationScheme : std::uint8_t {
  /// The paper's: a one-point rule per sub-facet (the curved patch's area at its centroid), split
  /// 1→4 while the estimate changes. The pieces must resolve the lobe to about one σ each. Kept
  /// so that the paper's Figure 4 stays reproducible, and for flat facets (NormalModel::Flat).
  Paper,
  /// A 16-point product Gauss rule (degree 7, triangle_rule.h) per piece over the exact surface
  /// map of the coarse facet (surface_map.h), its error estimated by the 9-point rule. Pieces are
  /// split 1→4 on their bounds alone, without a sample, until the rule can resolve them (the
  /// lobe to a few σ, no terminator, horizon or beam edge), then while the two rules disagree.
  /// The normal model is always the surface's (IntegratorOptions::normals applies to Paper only).
  Cubature,
  /// The lobe rule (lobe_rule.h) per piece over the exact surface map: six nodes, the specular
  /// lobe integrated in closed form about the piece's specular point, the piece clipped at the
  /// terminator, the horizon and the beam's edge. A piece's error is the change of its estimate
  /// when it is split 1→4 (the four children reuse its nodes: nine new ones). Pieces are split
  /// on their bounds alone until their normals spread less than 0.3 rad. The default.
  Lobe,
};

/// @brief The schemes' names in scene files and on the command line, in the enum's order.
std::vector<std::string> integrationSchemeNames();

/// @brief The scheme of that name, or nothing when no scheme has it.
std::optional<IntegrationScheme> integrationSchemeByName(std::string_view name);

/// @brief Accuracy settings of the per-observer integration.
///
/// The tolerance is relative to the observer's total: refinement stops once the sum of the
/// per-facet error estimates is at most max(tolerance × |E|, floor_w_m2). A facet's error
/// estimate is the paper's ΔE = |E_O − Σ E_On| where its centre sample resolves the lobe and the
/// distance (ResolutionLimits), and otherwise the larger of ΔE and a rigorous upper bound of
/// its contribution, so a glint that falls between samples is refined, never missed.
struct IntegratorOptions {
  double tolerance = 1e-3;  ///< relative accuracy asked of each observer's total
  double floor_w_m2 = 0.0;  ///< absolute accuracy for observers that see almost nothing
  int max_depth = 16;       ///< deepest 1→4 level of a coarse facet (4^16 sub-facets)
  std::int64_t max_evaluations = 4'000'000;    ///< per observer; beyond it: flagged unconverged
  NormalModel normals = NormalModel::Surface;  ///< normal the BRDF sees
  ResolutionLimits resolution;                 ///< when a centre sample stands for its facet
  /// Trace occlusion rays (Occluder) where the target can shadow itself: a facet counts only
  /// if its centre sees the laser and the observer. Off: every facet sees everything.
  bool occlusion = true;
  IntegrationScheme scheme = IntegrationScheme::Lobe;
  /// Triangles that shadow the beam and the reflected paths whatever `occlusion` says: the
  /// terrain. Null: none.
  std::shared_ptr<const ShadowMesh> terrain;
};

/// @brief The irradiance at one observer and how it was obtained.
struct ObserverResult {
  double irradiance_w_m2 = 0.0;
  double error_estimate_w_m2 = 0.0;  ///< Σ per-facet error estimates (see IntegratorOptions)
  std::int64_t evaluations = 0;      ///< reflection calculations (kernel evaluations)
  bool converged = true;             ///< error estimate within the requested accuracy
  bool depth_limited = false;        ///< some facet wanted to split beyond max_depth
};

/// @brief What the observer-independent culling did with the coarse facets.
struct CullStats {
  std::size_t coarse_facets = 0;
  std::size_t degenerate = 0;    ///< zero area: nothing to reflect
  std::size_t facing_away = 0;   ///< no normal of the facet can see the laser
  std::size_t outside_beam = 0;  ///< no point of the facet is inside the beam
  std::size_t behind_laser = 0;  ///< of those, the facet lies wholly behind the laser
  std::size_t shadowed = 0;      ///< its centre's ray to the laser hits the target or terrain
  std::size_t lit = 0;           ///< kept for the observers
  bool occlusion = false;        ///< occlusion rays are traced (see IntegratorOptions)
};

/// @brief A (sub)facet that observers may receive light from, with its bound geometry in its
/// object's frame. The lit coarse facets are the candidates of every observer; a block of the
/// observer field keeps those its bound cannot rule out, split finer where that tightens it,
/// and hands them down to its children.
struct Candidate {
  SubFacet facet;
  std::uint32_t object = 0;
  PatchGeometry geometry;  ///< with bounds
  /// Normal-cone half-angle and bounding radius of its coarse facet: however finely the facet
  /// is split, the light of the whole coarse facet spreads at least this wide.
  double fan_rad = 0.0;
  double fan_radius_m = 0.0;
};

/// @brief How boundBall() may trade candidates for work.
struct BallBoundOptions {
  /// Candidates whose bounds sum to at most this (with what the parents dropped) are dropped:
  /// every observer of the region may miss that much.
  double drop_allowance_w_m2 = 0.0;
  /// Distance between the region's samples: a coarse facet whose whole light could pass
  /// between them is reported in BallBound::narrow_w_m2.
  double sample_spacing_m = 0.0;
  /// Splitting a candidate to tighten the bound stops at this depth.
  int max_split_depth = 8;
};

/// @brief The bound of what any observer in a ball can receive (see boundBall()).
///
/// The bounds are never NaN. +∞ means unbounded: the ball reaches a lit facet (an observer on
/// the target sees unbounded irradiance in the point-source model), so nothing about the
/// ball may be decided from the bound or from samples: callers refine it.
struct BallBound {
  double upper_w_m2 = 0.0;    ///< no observer in the ball receives more (kept + dropped)
  double dropped_w_m2 = 0.0;  ///< bound of all dropped candidates, inherited ones included
  /// Bound of the kept candidates whose coarse facet's light is narrower than the sample
  /// spacing: a glint that samples alone could miss.
  double narrow_w_m2 = 0.0;
  /// The largest sample spacing at which none of those is narrow any more (the narrowest
  /// one's width / √3: a lattice that fine has a point inside its light); +∞ when none is.
  double resolving_spacing_m = std::numeric_limits<double>::infinity();
  std::int64_t bound_evaluations = 0;  ///< contribution bounds computed

  /// @brief False when the ball reaches a lit facet (upper_w_m2 is +∞).
  [[nodiscard]] bool bounded() const {
    return upper_w_m2 < std::numeric_limits<double>::infinity();
  }
};

namespace detail {
struct Workspace;
class DiffuseMomentCache;
struct ObserverSetting;
}  // namespace detail

/// @brief Per-thread scratch space of FacetIntegrator: reused between observers, so the hot
/// loop does not allocate once it has grown to the largest observer's needs.
class IntegratorWorkspace {
 public:
  IntegratorWorkspace();
  ~IntegratorWorkspace();
  IntegratorWorkspace(IntegratorWorkspace&&) noexcept;
  IntegratorWorkspace& operator=(IntegratorWorkspace&&) noexcept;

 private:
  friend class FacetIntegrator;
  std::unique_ptr<detail::Workspace> impl_;
};

class Occluder;
struct LitClusters;

/// @brief The lit coarse facets of a target under a beam, ready to be integrated at any
/// number of observers (from any number of threads, each with its own workspace).
class FacetIntegrator {
 public:
  /// @brief Culls the facets that no observer can receive light from (facing away from the
  /// laser, outside the beam, zero area, in the target's own shadow), once.
  FacetIntegrator(Target target, const Beam& beam, const IntegratorOptions& options);

  /// @brief Adaptive integration at @p observer_m (world coordinates).
  ///
  /// Where a material has several lobes (Material::terms()), each term is integrated on its own,
  /// to max(tolerance × its |E|, floor / the number of terms), and the results are summed: the
  /// total is then within tolerance × |E| + floor, its evaluations are the terms' together, and
  /// it is converged where each term is.
  ObserverResult adaptive(const Vec3& observer_m, IntegratorWorkspace& ws) const;

  /// @brief Adaptive integration at @p observer_m over @p candidates only (from
  /// boundBall() of a region that contains the observer), starting from their sub-facets.
  ObserverResult adaptive(const Vec3& observer_m, std::span<const Candidate> candidates,
                          IntegratorWorkspace& ws) const;

  /// @brief The lit coarse facets: every observer's candidates.
  [[nodiscard]] std::span<const Candidate> candidates() const { return lit_; }

  /// @brief Bounds what any observer within @p radius_m of @p centre_m can receive from
  /// @p inherited, and writes to @p kept the candidates that bound cannot drop. A candidate
  /// whose bound exceeds the drop allowance and whose normal cone is wider than the region
  /// looks from it is split 1→4 (up to BallBoundOptions::max_split_depth), which tightens the
  /// bound where the region sees only part of its light. @p inherited_dropped_w_m2 is what the
  /// parents already dropped. Never throws; allocates only when @p kept grows.
  BallBound boundBall(const Vec3& centre_m, double radius_m, std::span<const Candidate> inherited,
                      double inherited_dropped_w_m2, const BallBoundOptions& options,
                      std::vector<Candidate>& kept) const;

  /// @brief The uniform twin: every lit coarse facet split to @p level, each sub-facet
  /// evaluated once by the same kernel. Its error estimate is not computed (reported as 0).
  ObserverResult uniform(const Vec3& observer_m, int level, IntegratorWorkspace& ws) const;

  /// @brief Kernel evaluations spent so far on the lobe scheme's diffuse moments (each lit
  /// facet's once, when a far observer first needs it; shared by the withAccuracy() and
  /// withReturnExtinction() copies), which no observer's count includes. An integrator from
  /// withBeam() (an engagement's instant, which few observers share) computes none.
  [[nodiscard]] std::int64_t diffuseMomentEvaluations() const;

  [[nodiscard]] const CullStats& cullStats() const { return cull_; }
  [[nodiscard]] const IntegratorOptions& options() const { return options_; }
  [[nodiscard]] const Target& target() const { return *target_; }
  [[nodiscard]] const Beam& beam() const { return beam_; }

  /// @brief This integrator at another accuracy (IntegratorOptions::tolerance and floor_w_m2,
  /// which the culling does not depend on): the target, its culling, its occluder and surface
  /// maps are not built again, and the target itself is shared. What a scene's observer box
  /// and planes, each with its own accuracy, have in common. Throws std::invalid_argument
  /// where they are out of range, as the constructor does.
  [[nodiscard]] FacetIntegrator withAccuracy(double tolerance, double floor_w_m2) const;

  /// @brief This integrator under another beam (the same target moved, seen from its own frame:
  /// an engagement's instant, or with a swept beam an interval of it): culled again, the
  /// target, its surface maps and its occluder shared. The target's own shadow culls a facet
  /// only under a beam that is not swept (one shadow ray proves nothing for a set of beams).
  /// Throws std::invalid_argument as the constructor does.
  [[nodiscard]] FacetIntegrator withBeam(const Beam& beam) const;

  /// @brief This integrator with each reflected path attenuated by exp(−μ d), μ = @p per_m
  /// (Beam::return_extinction_per_m): 0 where intensity is read from a far plane.
  [[nodiscard]] FacetIntegrator withReturnExtinction(double per_m) const;

 private:
  // Readies the workspace for the observer and returns what a scheme sees of both, for the
  // materials' @p term at accuracy @p options.
  detail::ObserverSetting prepareObserver(const Vec3& observer_m, detail::Workspace& ws,
                                          const IntegratorOptions& options, std::size_t term) const;
  // One term's integration by the scheme of the options.
  static ObserverResult integrateTerm(const detail::ObserverSetting& setting,
                                      std::span<const Candidate> candidates, detail::Workspace& ws);
  // The culling (culling.cpp): lit_ and cull_ under beam_.
  void cull();
  // Builds occluder_ where the options and the target ask for it.
  void buildOccluder();
  // The lobe scheme's clusters_ over lit_ (culling.cpp), once cull() has found them.
  void buildClusters();
  // A diffuse moment cache for beam_ where the lobe scheme meets a diffuse material.
  void buildDiffuseMoments();

  // Shared by the copies withAccuracy() makes; the surface maps point into it.
  std::shared_ptr<const Target> target_;
  // Per material of the target, its terms (Material::terms()), and the most any has.
  std::shared_ptr<const std::vector<std::vector<Material>>> material_terms_;
  std::size_t term_count_ = 1;
  // Per term: whether some material's term of that rank has no closed form in the lobe rule
  // (Material::sampledOnly()); the lobe scheme hands such a term to the cubature rule.
  std::vector<char> term_sampled_;
  Beam beam_;
  IntegratorOptions options_;
  std::vector<Beam> object_beams_;  // the beam in each object's frame
  std::vector<Candidate> lit_;
  // Bounds over runs of lit_, for the observers that see every lit facet (lobe scheme).
  std::shared_ptr<const LitClusters> clusters_;
  // Per coarse facet, for the cubature and lobe schemes; geometry only, shared by the copies.
  std::shared_ptr<const std::vector<SurfaceMap>> maps_;
  CullStats cull_;
  std::shared_ptr<const Occluder> occluder_;  // null where the target cannot shadow itself
  // The lobe scheme's diffuse moments under beam_ (null without a diffuse term), shared by the
  // copies that keep the beam.
  std::shared_ptr<const detail::DiffuseMomentCache> diffuse_moments_;
  // Unique to this integrator: a workspace's geometry memo is kept while it serves the
  // same integrator (or a copy) and cleared when it moves to another.
  std::uint64_t id_ = 0;
};

}  // namespace glint
