#include "facets/material_fit.h"

#include <Eigen/Core>
#include <algorithm>
#include <cmath>
#include <limits>
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

// The parameters, each kept in its range by its form: per lobe ln ρ and ln σ, then ln A, ln B
// and logit(g / 4), then ln ρd.
Material materialOf(const Eigen::VectorXd& x, const MaterialFitModel& model) {
  Material m;
  int k = 0;
  for (int lobe = 0; lobe < model.lobes; ++lobe) {
    const SpecularLobe l{std::exp(x[k]), Beckmann{std::exp(x[k + 1])}};
    k += 2;
    if (lobe == 0) {
      m.specular_reflectance = l.reflectance;
      m.lobe = l.shape;
    } else {
      m.more_lobes.push_back(l);
    }
  }
  if (model.abg) {
    m.abg = AbgScatter{std::exp(x[k]), std::exp(x[k + 1]), 4.0 / (1.0 + std::exp(-x[k + 2]))};
    k += 3;
  }
  if (model.diffuse) m.diffuse_reflectance = std::exp(x[k]);
  return m;
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
  if (parameters == 0 || nodes.empty()) return best;
  // Starting widths: the lobes spread geometrically over a decade, the whole set tried at three
  // scales, since a lobe started far from its width can settle on the wrong peak.
  for (double scale : {0.003, 0.01, 0.04}) {
    Eigen::VectorXd x(parameters);
    int k = 0;
    for (int lobe = 0; lobe < model.lobes; ++lobe) {
      x[k++] = std::log(0.3 / model.lobes);
      x[k++] = std::log(scale * std::pow(10.0, static_cast<double>(lobe)));
    }
    if (model.abg) {
      x[k++] = std::log(1e-3);
      x[k++] = std::log(1e-3);
      x[k++] = 0.0;  // g = 2
    }
    if (model.diffuse) x[k++] = std::log(0.1);
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
  best.nodes = all.size();
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
  const Material& m = best.material;
  best.energy = m.totalSpecularReflectance() + m.diffuse_reflectance +
                (m.abg ? m.abg->totalIntegratedScatter() : 0.0);
  return best;
}

}  // namespace glint
