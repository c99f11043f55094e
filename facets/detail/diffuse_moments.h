#pragma once
// The diffuse light of a whole coarse facet at an observer far from it, from moments of the
// facet that no observer changes (the lobe scheme's shortcut for Lambertian light).
//
// A facet's diffuse irradiance at o is ∫ g(x) n(x)·(o − x) / |o − x|³ dA, where
// g = ρd E(x) cos θi(x) / π is the radiance the beam leaves on the surface: it depends on the
// beam and the facet only. Where the whole facet is lit (no terminator, no beam edge crosses
// it) and every normal of it faces o, the kernel K(y) = n·y / |y|³ at y = o − x is smooth over
// the facet, and its Taylor expansion about the facet's centre c to second order in δ = x − c
// needs only the moments ∫ g n, ∫ g n δᵀ and ∫ g n δ δᵀ (diffuseFromMoments() writes it out),
// with a remainder of at most (24 / 6) R³ G / (|r| − R)⁵ for r = o − c, G = ∫ g dA and R the
// facet's bounding radius about c (|∇³K[e, e, e]| ≤ 4! / |y|⁵ for unit n and e: see
// kThirdDerivativeBound). The moments are integrated once per facet, on demand (a degree-9
// rule on its four quarters, its error taken as the change from degree 7: 164 evaluations), so
// that a facet far from an observer costs no kernel evaluation there, where the rules cost 19
// or more: a diffuse target's glow, which every observer receives from every lit facet it
// sees, stops costing thousands of evaluations per point.

#include <array>
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <optional>
#include <vector>

#include "facets/beam.h"
#include "facets/material.h"
#include "facets/patch.h"
#include "facets/surface_map.h"
#include "facets/vec3.h"

namespace glint::detail {

using Tensor3 = std::array<std::array<std::array<double, 3>, 3>, 3>;

// The observer-independent moments of one coarse facet's diffuse radiance g (W/m²/sr).
struct DiffuseMoments {
  bool usable = false;  // false where the facet is not lit whole, or a node was invalid
  Vec3 centre_m{0.0};   // c: the facet's bounding ball (PatchGeometry)
  double radius_m = 0.0;
  double total = 0.0;                             // G = ∫ g dA, W/sr
  std::array<double, 3> first{};                  // m = ∫ g n dA
  std::array<std::array<double, 3>, 3> second{};  // M[k][l] = ∫ g n_k (x − c)_l dA, W m/sr
  Tensor3 third{};  // T[k][l][j] = ∫ g n_k (x − c)_l (x − c)_j dA, W m²/sr
  // The quadrature's error estimates (the change from the coarser rule).
  double total_error = 0.0;
  double first_error = 0.0;   // |Δm|
  double second_error = 0.0;  // ‖ΔM‖ (Frobenius)
  double third_error = 0.0;   // ‖ΔT‖ (Frobenius)
};

// An estimate of a facet's diffuse irradiance with its error bound (W/m²).
struct DiffuseEstimate {
  double irradiance_w_m2 = 0.0;
  double error_w_m2 = 0.0;
};

// The facet's diffuse irradiance at @p observer_m (its object's frame) from its moments, where
// every normal of @p g (the facet's bounds) faces the observer from every point of the facet
// and the observer lies beyond twice the facet's radius; nothing otherwise. Never throws.
std::optional<DiffuseEstimate> diffuseFromMoments(const DiffuseMoments& moments,
                                                  const PatchGeometry& g, const Vec3& observer_m);

// The moments of @p map's coarse facet under @p beam (the facet's object frame), bounded by
// @p g, with the material's diffuse reflectance; the kernel evaluations it took are added to
// @p evaluations.
DiffuseMoments diffuseMoments(const SurfaceMap& map, const PatchGeometry& g, const Beam& beam,
                              const Material& material, std::int64_t& evaluations);

// The moments of every coarse facet, each computed once, when an observer first asks for it
// (from any thread): the same values whichever thread computes them, so results do not depend
// on the order observers run in. Shared by the integrators that share a beam.
class DiffuseMomentCache {
 public:
  explicit DiffuseMomentCache(std::size_t facets)
      : moments_(facets), once_(std::make_unique<std::once_flag[]>(facets)) {}

  [[nodiscard]] const DiffuseMoments& get(const SurfaceMap& map, const PatchGeometry& g,
                                          const Beam& beam, const Material& material) const {
    const std::uint32_t k = map.facet();
    std::call_once(once_[k], [&] {
      std::int64_t evaluations = 0;
      // Held by pointer: only the facets far observers ask for take the ~0.4 kB.
      moments_[k] = std::make_unique<const DiffuseMoments>(
          diffuseMoments(map, g, beam, material, evaluations));
      evaluations_.fetch_add(evaluations, std::memory_order_relaxed);
    });
    return *moments_[k];
  }

  // Kernel evaluations spent on moments so far.
  [[nodiscard]] std::int64_t evaluations() const {
    return evaluations_.load(std::memory_order_relaxed);
  }

 private:
  mutable std::vector<std::unique_ptr<const DiffuseMoments>> moments_;
  std::unique_ptr<std::once_flag[]> once_;
  mutable std::atomic<std::int64_t> evaluations_{0};
};

}  // namespace glint::detail
