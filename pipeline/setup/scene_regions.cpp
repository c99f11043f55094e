#include "pipeline/setup/scene_regions.h"

#include <chrono>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/base/progress.h"

namespace glint {

Vec3 targetCentre(const Target& target) {
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (std::size_t f = 0; f < target.facetCount(); ++f) {
    const Vec3 origin = target.objects[target.object[f]].origin_m;
    for (const Vec3& c : target.corners_m[f]) {
      lo = glm::min(lo, origin + c);
      hi = glm::max(hi, origin + c);
    }
  }
  return target.facetCount() > 0 ? 0.5 * (lo + hi) : Vec3(0.0);
}

ObserverField sceneField(const FieldProblem& problem, const FieldSpec& spec, bool dense,
                         const WorkWatch& w, const char* noun) {
  WorkCounter counter;
  counter.stop = &w.watch.stopFlag();
  std::unique_ptr<ProgressReporter> progress;
  if (w.progress_to != nullptr)
    progress = std::make_unique<ProgressReporter>(*w.progress_to, w.terminal, noun, 0, counter);
  ObserverField field = [&] {
    try {
      return dense ? computeDenseField(problem.integrator, spec, problem.excluded, &counter)
                   : computeField(problem.integrator, spec, problem.excluded, &counter, w.exchange);
    } catch (const WorkStopped&) {
      if (progress) progress->stop();
      w.watch.check(w.what);
      throw;
    }
  }();
  progress.reset();
  requireFinite(field, w.what);
  return field;
}

void requireFinite(const ObserverField& field, const std::string& region) {
  const FieldStats& s = field.stats();
  if (s.non_finite_points > 0) {
    const Vec3& x = s.non_finite_at_m;
    throw std::runtime_error(region + ": " + std::to_string(s.non_finite_points) +
                             " points have a non-finite irradiance, one at (" +
                             formatNumber("%g", x.x) + ", " + formatNumber("%g", x.y) + ", " +
                             formatNumber("%g", x.z) + "); nothing was written");
  }
  if (!std::isfinite(s.peak_w_m2) || !(s.peak_w_m2 >= 0.0) ||
      std::isnan(s.unconverged_max_upper_w_m2)) {
    throw std::runtime_error(region +
                             ": the peak irradiance is not a finite number; nothing "
                             "was written");
  }
}

std::string farFieldDescription(const FarFieldSpec& spec) {
  return "the far field (6 × " + std::to_string(spec.face_pixels + 1) + "² directions)";
}

FarField sceneFarField(const SceneTarget& target, const Scene& scene, const WorkWatch& w) {
  // The reach hands over to the far field as near as a check lets it speak.
  const FarFieldSpec spec = scene.wantsReach() ? checkedFarFieldSpec(scene, target.integrator)
                                               : farFieldSpec(scene, target.integrator);
  requireWithinBudget(farFieldDescription(spec), farFieldMemoryFloorBytes(spec),
                      w.watch.budgetBytes(), "lower far_field.face_pixels, or raise --memory");

  WorkCounter counter;
  counter.stop = &w.watch.stopFlag();
  std::unique_ptr<ProgressReporter> progress;
  if (w.progress_to != nullptr) {
    progress =
        std::make_unique<ProgressReporter>(*w.progress_to, w.terminal, "directions", 0, counter);
  }
  FarField far = [&] {
    try {
      return computeFarField(target.integrator, spec, &counter, w.exchange);
    } catch (const WorkStopped&) {
      if (progress) progress->stop();
      w.watch.check(w.what);
      throw;
    }
  }();
  if (far.stats().non_finite_points > 0) {
    throw std::runtime_error("the far field: " + std::to_string(far.stats().non_finite_points) +
                             " directions have a non-finite intensity; nothing was written");
  }
  // A narrow glint's block a thousand far radii out never reaches the target: an unbounded
  // one is a fault, not a bound to report.
  if (!std::isfinite(far.peak().intensity_w_sr)) {
    throw std::runtime_error(
        "the far field: the peak intensity is not a finite number; nothing was written");
  }
  return far;
}

SceneReach sceneReach(const SceneTarget& target, const Scene& scene, const FarField& far,
                      const FarHazard& beyond, const WorkWatch& w) {
  const ReachSpec spec = reachSpec(scene, far);
  const FieldSpec face = reachFaceSpec(0, spec);
  const std::uint64_t far_bytes = farFieldMemoryFloorBytes(far.spec());
  const std::uint64_t face_bytes = fieldMemoryFloorBytes(face, false) + nearReachScratchBytes(spec);
  const std::string lattice = "6 × " + std::to_string(spec.face_cells + 1) + "² rays × " +
                              std::to_string(face.radial->layers + 1) + " layers from " +
                              formatNumber("%.3g", reachStartM(spec)) + " to " +
                              formatNumber("%.4g", spec.far_m) + " m";
  requireWithinBudget(w.what + " (" + lattice + ") beside the far field", far_bytes + face_bytes,
                      w.watch.budgetBytes(),
                      "lower reach.face_cells, raise reach.layer_ratio, or raise --memory");
  WorkCounter counter;
  counter.stop = &w.watch.stopFlag();
  counter.admit_bytes = [&watch = w.watch](std::uint64_t bytes) { return watch.admit(bytes); };
  std::unique_ptr<ProgressReporter> progress;
  if (w.progress_to != nullptr) {
    *w.progress_to << "glint run: " << w.what << ", " << lattice << "; memory: at least "
                   << formatBytes(static_cast<double>(far_bytes + face_bytes)) << " of the "
                   << formatBytes(static_cast<double>(w.watch.budgetBytes())) << " budget\n";
    progress =
        std::make_unique<ProgressReporter>(*w.progress_to, w.terminal, "reach points", 0, counter);
  }
  const FieldProblem problem = fieldProblem(target, scene, face);
  const auto start = std::chrono::steady_clock::now();
  SceneReach reach{[&] {
                     try {
                       return computeNearReach(problem.integrator, spec, problem.excluded, &counter,
                                               w.exchange);
                     } catch (const WorkStopped&) {
                       if (progress) progress->stop();
                       w.watch.check(w.what,
                                     "Raise --memory, or lower reach.face_cells, or raise "
                                     "reach.layer_ratio");
                       throw;
                     }
                   }(),
                   {},
                   0.0};
  if (progress) progress->stop();
  reach.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const auto summaries_start = std::chrono::steady_clock::now();
  const double mu = scene.hazard.atmosphere.extinction_per_m;
  const std::vector<FarReach> far_reach = beyond.byThreshold();
  for (std::size_t t = 0; t < spec.thresholds_w_m2.size(); ++t)
    reach.summaries.push_back(summarizeReach(reach.near, far, t, far_reach.at(t), mu));
  reach.summary_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - summaries_start).count();
  return reach;
}

}  // namespace glint
