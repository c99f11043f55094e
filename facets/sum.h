#pragma once
/// @file
/// @brief Compensated summation for totals of many terms of very different size.

#include <cmath>

namespace glint {

/// @brief Neumaier's variant of Kahan summation: the rounding error of every addition is
/// carried along, so the total is accurate to about one rounding of the result regardless of
/// the number of terms or their order of magnitude.
///
/// Non-finite terms are carried by the plain sum alone: a bound of +∞ (an observer touching
/// the target) must give a total of +∞, and the compensation would turn it into NaN (∞ − ∞),
/// which every comparison reads as false. So +∞ stays +∞, NaN stays NaN, and only +∞ + (−∞)
/// gives NaN, as in plain arithmetic. The same holds when finite terms overflow the sum.
class CompensatedSum {
 public:
  void add(double x) {
    const double t = sum_ + x;
    if (!std::isfinite(t)) {
      sum_ = t;
      return;
    }
    if (std::abs(sum_) >= std::abs(x)) {
      compensation_ += (sum_ - t) + x;
    } else {
      compensation_ += (x - t) + sum_;
    }
    sum_ = t;
  }
  [[nodiscard]] double value() const { return std::isfinite(sum_) ? sum_ + compensation_ : sum_; }

 private:
  double sum_ = 0.0;
  double compensation_ = 0.0;
};

}  // namespace glint
