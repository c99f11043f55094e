#pragma once
/// @file
/// @brief Compensated summation for totals of many terms of very different size.

#include <cmath>

namespace glint {

/// @brief Neumaier's variant of Kahan summation: the rounding error of every addition is
/// carried along, so the total is accurate to about one rounding of the result regardless of
/// the number of terms or their order of magnitude.
class CompensatedSum {
 public:
  void add(double x) {
    const double t = sum_ + x;
    if (std::abs(sum_) >= std::abs(x)) {
      compensation_ += (sum_ - t) + x;
    } else {
      compensation_ += (x - t) + sum_;
    }
    sum_ = t;
  }
  [[nodiscard]] double value() const { return sum_ + compensation_; }

 private:
  double sum_ = 0.0;
  double compensation_ = 0.0;
};

}  // namespace glint
