#include "facets/integrator.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <stdexcept>

#include "facets/detail/diffuse_moments.h"
#include "facets/detail/patch_models.h"
#include "facets/detail/schemes.h"
#include "facets/detail/workspace.h"
#include "facets/sum.h"

namespace glint {

std::vector<std::string> integrationSchemeNames() { return {"paper", "cubature", "lobe"}; }

std::optional<IntegrationScheme> integrationSchemeByName(std::string_view name) {
  const std::vector<std::string> names = integrationSchemeNames();
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) return std::nullopt;
  return static_cast<IntegrationScheme>(it - names.begin());
}

IntegratorWorkspace::IntegratorWorkspace() : impl_(std::make_unique<detail::Workspace>()) {}
IntegratorWorkspace::~IntegratorWorkspace() = default;
IntegratorWorkspace::IntegratorWorkspace(IntegratorWorkspace&&) noexcept = default;
IntegratorWorkspace& IntegratorWorkspace::operator=(IntegratorWorkspace&&) noexcept = default;

namespace {

void validateAccuracy(const IntegratorOptions& o) {
  if (!(o.tolerance >= 0.0) || !(o.floor_w_m2 >= 0.0) || !std::isfinite(o.floor_w_m2) ||
      o.max_depth < 0 || o.max_depth > 30 || o.max_evaluations < 1) {
    throw std::invalid_argument("FacetIntegrator: accuracy options out of range");
  }
}

// Light is never negative: a sum of positive pieces and rules' corrections that cancel to
// round-off (about 1e-17 W/m² where a disk is seen edge-on) reads 0, which is also nearer the
// truth, so the error estimate still holds.
ObserverResult nonNegative(ObserverResult r) {
  if (r.irradiance_w_m2 < 0.0) r.irradiance_w_m2 = 0.0;
  return r;
}

}  // namespace

FacetIntegrator FacetIntegrator::withAccuracy(double tolerance, double floor_w_m2) const {
  FacetIntegrator copy = *this;  // the target shared; culling, maps and occluder as they are
  copy.options_.tolerance = tolerance;
  copy.options_.floor_w_m2 = floor_w_m2;
  validateAccuracy(copy.options_);
  return copy;
}

FacetIntegrator FacetIntegrator::withReturnExtinction(double per_m) const {
  FacetIntegrator copy = *this;  // the surface maps hold geometry only: shared as they are
  copy.beam_.return_extinction_per_m = per_m;
  for (Beam& b : copy.object_beams_) b.return_extinction_per_m = per_m;
  return copy;
}

FacetIntegrator::FacetIntegrator(Target target, const Beam& beam, const IntegratorOptions& options)
    : target_(std::make_shared<const Target>(std::move(target))), beam_(beam), options_(options) {
  static std::atomic<std::uint64_t> instances{0};
  id_ = ++instances;
  validateAccuracy(options_);
  auto terms = std::make_shared<std::vector<std::vector<Material>>>();
  for (const Material& m : target_->materials) {
    terms->push_back(m.terms());
    term_count_ = std::max(term_count_, terms->back().size());
  }
  term_sampled_.assign(term_count_, 0);
  for (const std::vector<Material>& t : *terms) {
    for (std::size_t k = 0; k < t.size(); ++k) {
      if (t[k].sampledOnly()) term_sampled_[k] = 1;
    }
  }
  material_terms_ = std::move(terms);
  object_beams_.reserve(target_->objects.size());
  for (const TargetObject& obj : target_->objects) {
    object_beams_.push_back(beam_.relativeTo(obj.origin_m));
  }
  buildOccluder();
  cull();
  auto maps = std::make_shared<std::vector<SurfaceMap>>();
  if (options_.scheme != IntegrationScheme::Paper) {
    maps->reserve(target_->facetCount());
    for (std::uint32_t i = 0; i < target_->facetCount(); ++i) maps->emplace_back(*target_, i);
  }
  maps_ = std::move(maps);
  if (options_.scheme == IntegrationScheme::Lobe) buildClusters();
  buildDiffuseMoments();
}

std::int64_t FacetIntegrator::diffuseMomentEvaluations() const {
  return diffuse_moments_ ? diffuse_moments_->evaluations() : 0;
}

void FacetIntegrator::buildDiffuseMoments() {
  const bool diffuse = std::any_of(target_->materials.begin(), target_->materials.end(),
                                   [](const Material& m) { return m.diffuse_reflectance > 0.0; });
  if (options_.scheme == IntegrationScheme::Lobe && diffuse) {
    diffuse_moments_ = std::make_shared<const detail::DiffuseMomentCache>(target_->facetCount());
  }
}

FacetIntegrator FacetIntegrator::withBeam(const Beam& beam) const {
  FacetIntegrator copy = *this;  // the target, maps and occluder shared: geometry only
  copy.beam_ = beam;
  copy.object_beams_.clear();
  for (const TargetObject& obj : target_->objects) {
    copy.object_beams_.push_back(beam.relativeTo(obj.origin_m));
  }
  copy.lit_.clear();
  copy.clusters_.reset();
  copy.cull_ = CullStats{};
  copy.cull();
  if (options_.scheme == IntegrationScheme::Lobe) copy.buildClusters();
  // An instant's beam serves the few observers of that instant: the moments (164 evaluations a
  // facet) would cost more than they save.
  copy.diffuse_moments_.reset();
  return copy;
}

detail::ObserverSetting FacetIntegrator::prepareObserver(const Vec3& observer_m,
                                                         detail::Workspace& ws,
                                                         const IntegratorOptions& options,
                                                         std::size_t term) const {
  ws.surfaces.bind(id_);
  ws.observer_local_m.resize(target_->objects.size());
  for (std::size_t k = 0; k < target_->objects.size(); ++k) {
    ws.observer_local_m[k] = observer_m - target_->objects[k].origin_m;
  }
  return {*target_,        options, *material_terms_,    term,
          object_beams_,   *maps_,  ws.observer_local_m, observer_m,
          occluder_.get(), lit_,    clusters_.get(),     diffuse_moments_.get()};
}

ObserverResult FacetIntegrator::adaptive(const Vec3& observer_m,
                                         IntegratorWorkspace& workspace) const {
  return adaptive(observer_m, lit_, workspace);
}

ObserverResult FacetIntegrator::adaptive(const Vec3& observer_m,
                                         std::span<const Candidate> candidates,
                                         IntegratorWorkspace& workspace) const {
  detail::Workspace& ws = *workspace.impl_;
  const bool lobe = options_.scheme == IntegrationScheme::Lobe;
  if (term_count_ == 1 && !(lobe && term_sampled_[0] != 0)) {
    return nonNegative(integrateTerm(prepareObserver(observer_m, ws, options_, 0), candidates, ws));
  }
  // The light is linear in the BRDF: each term on its own, with a share of the floor and what
  // is left of the evaluations, and their sum. A term the lobe rule has no closed form for (ABg,
  // a table) is sampled by the cubature rule instead.
  ObserverResult total;
  for (std::size_t term = 0; term < term_count_; ++term) {
    IntegratorOptions options = options_;
    options.floor_w_m2 = options_.floor_w_m2 / static_cast<double>(term_count_);
    options.max_evaluations =
        std::max<std::int64_t>(1, options_.max_evaluations - total.evaluations);
    if (lobe && term_sampled_[term] != 0) options.scheme = IntegrationScheme::Cubature;
    const ObserverResult r =
        integrateTerm(prepareObserver(observer_m, ws, options, term), candidates, ws);
    total.irradiance_w_m2 += r.irradiance_w_m2;
    total.error_estimate_w_m2 += r.error_estimate_w_m2;
    total.evaluations += r.evaluations;
    total.converged = total.converged && r.converged;
    total.depth_limited = total.depth_limited || r.depth_limited;
  }
  return nonNegative(total);
}

ObserverResult FacetIntegrator::integrateTerm(const detail::ObserverSetting& setting,
                                              std::span<const Candidate> candidates,
                                              detail::Workspace& ws) {
  // The scheme is chosen here, once per observer: each runs the refinement engine compiled with
  // its own rule (detail/schemes.h).
  switch (setting.options.scheme) {
    case IntegrationScheme::Paper:
      return detail::integratePaper(setting, candidates, ws);
    case IntegrationScheme::Cubature:
      return detail::integrateCubature(setting, candidates, ws);
    case IntegrationScheme::Lobe:
      return detail::integrateLobe(setting, candidates, ws);
  }
  throw std::logic_error("FacetIntegrator: unknown integration scheme");
}

ObserverResult FacetIntegrator::uniform(const Vec3& observer_m, int level,
                                        IntegratorWorkspace& workspace) const {
  if (level < 0 || level > 30) throw std::invalid_argument("uniform level out of range");
  detail::Workspace& ws = *workspace.impl_;
  ObserverResult result;
  CompensatedSum total;
  const detail::ObserverSetting setting = prepareObserver(observer_m, ws, options_, 0);
  detail::forEachSeen(setting, lit_, [&](const Candidate& lit, const detail::Frame& f) {
    // The kernel takes every lobe of the material at once (its BRDF is their sum).
    const Material& material = target_->materials[target_->objects[lit.object].material];
    detail::withPatchModel(*target_, lit.facet.coarse, [&](const auto& model) {
      ws.stack.clear();
      ws.stack.push_back(lit.facet);
      while (!ws.stack.empty()) {
        const SubFacet sub = ws.stack.back();
        ws.stack.pop_back();
        if (sub.depth == level) {
          total.add(facetIrradiance(model.template geometry<false>(sub, options_.normals),
                                    f.observer_m, f.beam, material));
          ++result.evaluations;
        } else {
          for (const SubFacet& c : model.split(sub)) ws.stack.push_back(c);
        }
      }
    });
  });
  result.irradiance_w_m2 = total.value();
  return result;
}

}  // namespace glint
