#include "facets/material_fit.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <unsupported/Eigen/NonLinearOptimization>
#include <unsupported/Eigen/NumericalDiff>
#include <vector>

namespace glint {
namespace {

// A node of the table the fit sees: its directions (normal +z) and ln(f + floor).
struct Node {
  Vec3 wi, wo;
  double f = 0.0;
  double log_f = 0.0;
};

// Each parameter's range: what a scene's reader takes (pipeline/input/scene.cpp), narrowed
// where a table cannot tell values apart anyway, so that every fit is a material a scene takes
// and no parameter runs off to 0 or to overflow (a constant table once gave B = 0, A = 8.75e42).
struct Range {
  double lo, hi;
};
constexpr Range kReflectance{1e-12, 1.0};  // a lobe's ρ, ρd
constexpr Range kSigma{1e-4, 2.0};         // Beckmann σ: finer than any table's step resolves
constexpr Range kAbgPeak{1e-12, 1e10};     // A/B (1/sr): the reader's bound
constexpr Range kAbgWidth{1e-4, 1.0};      // B^(1/g) / (2 max(1, g)), rad
constexpr double kAbgMinB = 1e-12, kAbgMaxA = 1e6;

// A free variable onto [lo, hi], logarithmically, and back.
double onto(double x, Range r) {
  const double t = 1.0 / (1.0 + std::exp(-x));
  return std::exp(std::log(r.lo) + t * (std::log(r.hi) - std::log(r.lo)));
}
double from(double v, Range r) {
  const double t = (std::log(v) - std::log(r.lo)) / (std::log(r.hi) - std::log(r.lo));
  return std::log(t / (1.0 - t));
}

// ABg from its peak A/B, its width and g: B = (2 max(1, g) w)^g, so that the width is the
// free variable the lobes' σ is, and the peak stays where the reader's bound on A/B is.
AbgScatter abgOf(double peak_per_sr, double width_rad, double g) {
  const double b = std::max(kAbgMinB, std::pow(2.0 * std::max(1.0, g) * width_rad, g));
  return AbgScatter{std::min(peak_per_sr * b, kAbgMaxA), b, g};
}

// The parameters, each kept in its range by its form: per lobe ρ and σ, then ABg's peak, width
// and g (logit of g / 4), then ρd.
Material materialOf(const Eigen::VectorXd& x, const MaterialFitModel& model) {
  Material m;
  int k = 0;
  for (int lobe = 0; lobe < model.lobes; ++lobe) {
    const SpecularLobe l{onto(x[k], kReflectance), Beckmann{onto(x[k + 1], kSigma)}};
    k += 2;
    if (lobe == 0) {
      m.specular_reflectance = l.reflectance;
      m.lobe = l.shape;
    } else {
      m.more_lobes.push_back(l);
    }
  }
  if (model.abg) {
    m.abg =
        abgOf(onto(x[k], kAbgPeak), onto(x[k + 1], kAbgWidth), 4.0 / (1.0 + std::exp(-x[k + 2])));
    k += 3;
  }
  if (model.diffuse) m.diffuse_reflectance = onto(x[k], kReflectance);
  return m;
}

// Terms the fit drove to nothing (below this share of the light it reflects) are left out, and
// named: a lobe of ρ 1e-12 only costs the integrator its bounds.
constexpr double kNegligibleShare = 1e-6;

// @p m without its negligible terms, each named in @p dropped.
Material withoutNegligibleTerms(const Material& m, double energy,
                                std::vector<std::string>& dropped) {
  const auto negligible = [&](double share) { return share < kNegligibleShare * energy; };
  const auto number = [](double v) {
    char buf[32];
    std::snprintf(buf, sizeof buf, "%.3g", v);
    return std::string(buf);
  };
  std::vector<SpecularLobe> lobes;
  if (m.specular_reflectance > 0.0) lobes.push_back({m.specular_reflectance, m.lobe});
  lobes.insert(lobes.end(), m.more_lobes.begin(), m.more_lobes.end());
  Material out;
  out.diffuse_reflectance = m.diffuse_reflectance;
  std::vector<SpecularLobe> kept;
  for (std::size_t k = 0; k < lobes.size(); ++k) {
    if (negligible(lobes[k].reflectance)) {
      dropped.push_back("lobe " + std::to_string(k + 1) + " (ρ " + number(lobes[k].reflectance) +
                        ", σ " + number(lobes[k].shape.sigma) + ")");
    } else {
      kept.push_back(lobes[k]);
    }
  }
  if (!kept.empty()) {
    out.specular_reflectance = kept[0].reflectance;
    out.lobe = kept[0].shape;
    out.more_lobes.assign(kept.begin() + 1, kept.end());
  }
  if (m.abg) {
    if (negligible(m.abg->totalIntegratedScatter())) {
      dropped.push_back("ABg (total integrated scatter " + number(m.abg->totalIntegratedScatter()) +
                        ")");
    } else {
      out.abg = m.abg;
    }
  }
  if (m.diffuse_reflectance > 0.0 && negligible(m.diffuse_reflectance)) {
    dropped.push_back("the Lambertian part (ρd " + number(m.diffuse_reflectance) + ")");
    out.diffuse_reflectance = 0.0;
  }
  return out;
}

double brdfOf(const Material& m, const Node& n) {
  const Vec3 normal(0.0, 0.0, 1.0);
  const double cos_i = n.wi.z, cos_r = n.wo.z;
  return m.cosineWeightedBrdf(normal, n.wi, n.wo, cos_i, cos_r) / (cos_i * cos_r);
}

// The residuals ln(f_fit + floor) − ln(f_table + floor), as Eigen's Levenberg–Marquardt wants
// them (its numerical Jacobian by forward differences).
struct Residuals {
  using Scalar = double;
  using InputType = Eigen::VectorXd;
  using ValueType = Eigen::VectorXd;
  using JacobianType = Eigen::MatrixXd;
  enum { InputsAtCompileTime = Eigen::Dynamic, ValuesAtCompileTime = Eigen::Dynamic };

  const std::vector<Node>* nodes;
  const MaterialFitModel* model;
  double floor;
  int parameters;

  [[nodiscard]] int inputs() const { return parameters; }
  [[nodiscard]] int values() const { return static_cast<int>(nodes->size()); }
  int operator()(const Eigen::VectorXd& x, Eigen::VectorXd& r) const {
    const Material m = materialOf(x, *model);
    for (std::size_t j = 0; j < nodes->size(); ++j) {
      const double f = brdfOf(m, (*nodes)[j]);
      // A parameter driven to overflow reads as a poor fit, never as a NaN.
      r[static_cast<Eigen::Index>(j)] =
          std::isfinite(f) ? std::log(f + floor) - (*nodes)[j].log_f : 1e3;
    }
    return 0;
  }
};

// At most this many nodes, spread evenly through the table: enough for 12 parameters.
constexpr std::size_t kMaxFitNodes = 40000;

}  // namespace

MaterialFit fitMaterial(const BrdfTable& table, const MaterialFitModel& model) {
  std::vector<Node> all;
  double peak = 0.0;
  for (double ti : table.givenAxis(0)) {
    for (double to : table.givenAxis(1)) {
      if (ti > 89.5 * kPi / 180.0 || to > 89.5 * kPi / 180.0) continue;
      for (double p : table.givenAxis(2)) {
        Node n;
        n.wi = Vec3(std::sin(ti), 0.0, std::cos(ti));
        n.wo = Vec3(std::sin(to) * std::cos(p), std::sin(to) * std::sin(p), std::cos(to));
        n.f = table.brdf(ti, to, p);
        peak = std::max(peak, n.f);
        all.push_back(n);
      }
    }
  }
  const double floor = 1e-6 * peak;
  std::vector<Node> nodes;
  const std::size_t stride = std::max<std::size_t>(1, all.size() / kMaxFitNodes);
  for (std::size_t j = 0; j < all.size(); j += stride) nodes.push_back(all[j]);
  for (Node& n : nodes) n.log_f = std::log(n.f + floor);

  const int parameters = 2 * model.lobes + (model.abg ? 3 : 0) + (model.diffuse ? 1 : 0);
  MaterialFit best;
  best.rms_log_error = std::numeric_limits<double>::infinity();
  best.parameters = parameters;
  best.nodes = all.size();
  // Fewer nodes than parameters settle nothing: the caller refuses such a fit.
  if (parameters == 0 || all.size() < static_cast<std::size_t>(parameters)) return best;
  // Starting widths: the lobes spread geometrically over a decade, the whole set tried at three
  // scales, since a lobe started far from its width can settle on the wrong peak.
  for (double scale : {0.003, 0.01, 0.04}) {
    Eigen::VectorXd x(parameters);
    int k = 0;
    for (int lobe = 0; lobe < model.lobes; ++lobe) {
      x[k++] = from(0.3 / model.lobes, kReflectance);
      x[k++] = from(scale * std::pow(10.0, static_cast<double>(lobe)), kSigma);
    }
    if (model.abg) {
      x[k++] = from(1.0, kAbgPeak);      // A = B = 1e-3
      x[k++] = from(0.0079, kAbgWidth);  // √1e-3 / 4
      x[k++] = 0.0;                      // g = 2
    }
    if (model.diffuse) x[k++] = from(0.1, kReflectance);
    Residuals residuals{&nodes, &model, floor, parameters};
    Eigen::NumericalDiff<Residuals> diff(residuals);
    Eigen::LevenbergMarquardt<Eigen::NumericalDiff<Residuals>> lm(diff);
    lm.parameters.maxfev = 400 * parameters;
    lm.minimize(x);
    Eigen::VectorXd r(static_cast<Eigen::Index>(nodes.size()));
    residuals(x, r);
    const double rms = std::sqrt(r.squaredNorm() / static_cast<double>(nodes.size()));
    if (rms < best.rms_log_error) {
      best.material = materialOf(x, model);
      best.rms_log_error = rms;
    }
  }
  // Its errors over every node, not only those it was fitted on.
  double sum2 = 0.0;
  best.max_relative_error = 0.0;
  for (const Node& n : all) {
    const double f = brdfOf(best.material, n);
    const double d = std::log(f + floor) - std::log(n.f + floor);
    sum2 += d * d;
    if (n.f >= 0.01 * peak)
      best.max_relative_error = std::max(best.max_relative_error, std::abs(f / n.f - 1.0));
  }
  best.rms_log_error = std::sqrt(sum2 / static_cast<double>(all.size()));
  const auto energyOf = [](const Material& m) {
    return m.totalSpecularReflectance() + m.diffuse_reflectance +
           (m.abg ? m.abg->totalIntegratedScatter() : 0.0);
  };
  best.material = withoutNegligibleTerms(best.material, energyOf(best.material), best.dropped);
  best.energy = energyOf(best.material);
  return best;
}

}  // namespace glint
