#include "pipeline/report/unlit_warning.h"

#include <optional>

#include "pipeline/base/number_format.h"

namespace glint {
namespace {

// "12 of its 40 coarse facets " + what.
std::string count(std::size_t n, std::size_t of, const std::string& what) {
  return std::to_string(n) + " of its " + std::to_string(of) + " coarse facets " + what;
}

// How far (m) the ground stands above @p p, if it does.
std::optional<double> depthBelowGround(const Terrain& terrain, const Vec3& p) {
  const std::optional<double> ground = terrain.surfaceZ(p.x, p.y);
  if (ground && *ground > p.z) return *ground - p.z;
  return std::nullopt;
}

}  // namespace

std::vector<std::string> unlitTargetWarnings(const Scene& scene, const CullStats& cull) {
  if (cull.lit > 0 || cull.coarse_facets == 0) return {};
  const std::size_t n = cull.coarse_facets;
  std::vector<std::string> why;
  if (cull.behind_laser > 0) why.push_back(count(cull.behind_laser, n, "lie behind the laser"));
  if (cull.outside_beam > cull.behind_laser) {
    why.push_back(count(cull.outside_beam - cull.behind_laser, n, "lie outside the beam"));
  }
  if (cull.facing_away > 0) why.push_back(count(cull.facing_away, n, "face away from the laser"));
  if (cull.shadowed > 0) {
    why.push_back(count(cull.shadowed, n,
                        scene.terrain ? "are in the terrain's shadow (the ground lies between "
                                        "them and the laser)"
                                      : "are in the target's own shadow"));
  }
  if (cull.degenerate > 0) why.push_back(count(cull.degenerate, n, "have no area"));
  if (scene.terrain) {
    for (std::size_t i = 0; i < scene.objects.size(); ++i) {
      if (const auto d = depthBelowGround(*scene.terrain, scene.objects[i].centre_m())) {
        why.push_back("object " + std::to_string(i) + "'s centre lies " + formatNumber("%.3g", *d) +
                      " m below the ground");
      }
    }
    if (const auto d = depthBelowGround(*scene.terrain, scene.laser.origin_m))
      why.push_back("the laser lies " + formatNumber("%.3g", *d) + " m below the ground");
  }
  std::string text = "no facet of the target is lit";
  for (std::size_t k = 0; k < why.size(); ++k) text += (k == 0 ? ": " : "; ") + why[k];
  text +=
      ". Nothing reflects, so the empty result says nothing of the hazard: it is not a safe "
      "one. Check the laser's position and direction, the objects' positions and the terrain";
  return {text};
}

}  // namespace glint
