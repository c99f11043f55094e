#include "facets/lit_ball.h"

#include <algorithm>
#include <limits>

namespace glint {

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

}  // namespace glint
