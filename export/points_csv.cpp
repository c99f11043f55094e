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

void appendValue(std::string& line, const CsvColumn& c, std::size_t i) {
  if (c.integer) {
    line += std::to_string(static_cast<long long>(c.values[i]));
  } else {
    appendNumber(line, c.values[i]);
  }
}

// Every column has one finite value per row.
void requireFiniteColumns(std::span<const CsvColumn> columns, std::size_t rows) {
  for (const CsvColumn& c : columns) {
    if (c.values.size() != rows) throw OutputError(c.name + ": one value per observer");
    for (std::size_t i = 0; i < c.values.size(); ++i) {
      if (!std::isfinite(c.values[i])) {
        throw OutputError("observer " + std::to_string(i + 1) + ": " + c.name +
                          " is not finite; nothing was written");
      }
    }
  }
}

}  // namespace

void writeColumnsCsv(std::ostream& out, std::span<const Vec3> points_m,
                     std::span<const CsvColumn> columns) {
  requireFiniteColumns(columns, points_m.size());
  std::string text = "x,y,z";
  for (const CsvColumn& c : columns) text += "," + c.name;
  text += '\n';
  text.reserve(text.size() + (72 + 24 * columns.size()) * points_m.size());
  for (std::size_t i = 0; i < points_m.size(); ++i) {
    const Vec3& p = points_m[i];
    appendNumber(text, p.x);
    for (double v : {p.y, p.z}) {
      text += ',';
      appendNumber(text, v);
    }
    for (const CsvColumn& c : columns) {
      text += ',';
      appendValue(text, c, i);
    }
    text += '\n';
  }
  out << text;
}

void writePointsCsv(std::ostream& out, std::span<const Vec3> points_m,
                    std::span<const ObserverResult> results, std::span<const CsvColumn> extra) {
  if (points_m.size() != results.size()) throw OutputError("points and results differ in count");
  std::vector<CsvColumn> columns{{"irradiance_w_m2", {}},
                                 {"error_estimate_w_m2", {}},
                                 {"evaluations", {}, true},
                                 {"converged", {}, true}};
  for (const ObserverResult& r : results) {
    columns[0].values.push_back(r.irradiance_w_m2);
    columns[1].values.push_back(r.error_estimate_w_m2);
    columns[2].values.push_back(static_cast<double>(r.evaluations));
    columns[3].values.push_back(r.converged ? 1.0 : 0.0);
  }
  columns.insert(columns.end(), extra.begin(), extra.end());
  writeColumnsCsv(out, points_m, columns);
}

}  // namespace glint
