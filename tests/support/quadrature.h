#pragma once
// Reference quadrature for the tests: independent of the code under test.

#include <cmath>
#include <functional>
#include <utility>
#include <vector>

namespace glint::test {

// Composite Simpson rule on [a, b] with n (even) intervals: error ≤ (b − a) h⁴ max|f⁗| / 180.
inline double simpson(const std::function<double(double)>& f, double a, double b, int n) {
  if (n % 2 != 0) ++n;
  const double h = (b - a) / n;
  double sum = f(a) + f(b);
  for (int i = 1; i < n; ++i) sum += f(a + i * h) * (i % 2 == 1 ? 4.0 : 2.0);
  return sum * h / 3.0;
}

// Gauss–Legendre nodes and weights on [−1, 1] (Newton on the Legendre recurrence).
inline std::vector<std::pair<double, double>> gaussLegendre(int n) {
  std::vector<std::pair<double, double>> nodes;
  for (int i = 1; i <= n; ++i) {
    double x = std::cos(M_PI * (i - 0.25) / (n + 0.5));
    double dp = 0.0;
    for (int iter = 0; iter < 100; ++iter) {
      double p0 = 1.0, p1 = x;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      dp = n * (x * p1 - p0) / (x * x - 1.0);
      const double dx = p1 / dp;
      x -= dx;
      if (std::abs(dx) < 1e-16) break;
    }
    nodes.push_back({x, 2.0 / ((1.0 - x * x) * dp * dp)});
  }
  return nodes;
}

}  // namespace glint::test
