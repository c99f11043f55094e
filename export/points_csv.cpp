#include "export/points_csv.h"

#include <charconv>
#include <cmath>
#include <string>

#include "export/atomic_file.h"

namespace glint {
namespace {

void appendNumber(std::string& line, double x) {
  char buf[32];
  const auto res = std::to_chars(buf, buf + sizeof buf, x);
  line.append(buf, res.ptr);
}

}  // namespace

void writePointsCsv(std::ostream& out, std::span<const Vec3> points_m,
                    std::span<const ObserverResult> results, std::span<const CsvColumn> extra) {
  if (points_m.size() != results.size()) throw OutputError("points and results differ in count");
  for (const CsvColumn& c : extra) {
    if (c.values.size() != results.size()) throw OutputError(c.name + ": one value per observer");
    for (std::size_t i = 0; i < c.values.size(); ++i) {
      if (!std::isfinite(c.values[i])) {
        throw OutputError("observer " + std::to_string(i + 1) + ": " + c.name +
                          " is not finite; nothing was written");
      }
    }
  }
  for (std::size_t i = 0; i < results.size(); ++i) {
    if (!std::isfinite(results[i].irradiance_w_m2) ||
        !std::isfinite(results[i].error_estimate_w_m2)) {
      throw OutputError("observer " + std::to_string(i + 1) +
                        " has a non-finite result; nothing was written");
    }
  }
  std::string text = "x,y,z,irradiance_w_m2,error_estimate_w_m2,evaluations,converged";
  for (const CsvColumn& c : extra) text += "," + c.name;
  text += '\n';
  text.reserve(text.size() + (96 + 24 * extra.size()) * results.size());
  for (std::size_t i = 0; i < results.size(); ++i) {
    const Vec3& p = points_m[i];
    const ObserverResult& r = results[i];
    for (double v : {p.x, p.y, p.z, r.irradiance_w_m2, r.error_estimate_w_m2}) {
      appendNumber(text, v);
      text += ',';
    }
    text += std::to_string(r.evaluations);
    text += r.converged ? ",1" : ",0";
    for (const CsvColumn& c : extra) {
      text += ',';
      appendNumber(text, c.values[i]);
    }
    text += '\n';
  }
  out << text;
}

}  // namespace glint
