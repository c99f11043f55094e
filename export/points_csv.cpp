#include "export/points_csv.h"

#include <charconv>
#include <cmath>
#include <string>
#include <vector>

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

// Observer @p row's @p name is finite, or nothing is written.
void requireFinite(double value, std::size_t row, const std::string& name) {
  if (!std::isfinite(value)) {
    throw OutputError("observer " + std::to_string(row + 1) + ": " + name +
                      " is not finite; nothing was written");
  }
}

// Every column has one finite value per row.
void requireFiniteColumns(std::span<const CsvColumn> columns, std::size_t rows) {
  for (const CsvColumn& c : columns) {
    if (c.values.size() != rows) throw OutputError(c.name + ": one value per observer");
    for (std::size_t i = 0; i < c.values.size(); ++i) requireFinite(c.values[i], i, c.name);
  }
}

// Writes the header x,y,z and @p names, then per row its point and what @p append_row(line, i)
// appends (each value led by a comma). Rows go out a megabyte at a time, not as one text of the
// whole table: a table of millions of rows would otherwise hold its size again in memory.
template <class AppendRow>
void writeRows(std::ostream& out, std::span<const Vec3> points_m,
               const std::vector<std::string>& names, AppendRow append_row) {
  constexpr std::size_t kChunkBytes = std::size_t{1} << 20;
  std::string text = "x,y,z";
  for (const std::string& name : names) text += "," + name;
  text += '\n';
  text.reserve(kChunkBytes + 4096);
  for (std::size_t i = 0; i < points_m.size(); ++i) {
    const Vec3& p = points_m[i];
    appendNumber(text, p.x);
    for (double v : {p.y, p.z}) {
      text += ',';
      appendNumber(text, v);
    }
    append_row(text, i);
    text += '\n';
    if (text.size() >= kChunkBytes) {
      out << text;
      text.clear();
    }
  }
  out << text;
}

std::vector<std::string> namesOf(std::span<const CsvColumn> columns) {
  std::vector<std::string> names;
  for (const CsvColumn& c : columns) names.push_back(c.name);
  return names;
}

}  // namespace

void writeColumnsCsv(std::ostream& out, std::span<const Vec3> points_m,
                     std::span<const CsvColumn> columns) {
  requireFiniteColumns(columns, points_m.size());
  writeRows(out, points_m, namesOf(columns), [&](std::string& line, std::size_t i) {
    for (const CsvColumn& c : columns) {
      line += ',';
      appendValue(line, c, i);
    }
  });
}

void writePointsCsv(std::ostream& out, std::span<const Vec3> points_m,
                    std::span<const ObserverResult> results, std::span<const CsvColumn> extra) {
  if (points_m.size() != results.size()) throw OutputError("points and results differ in count");
  for (std::size_t i = 0; i < results.size(); ++i) {
    requireFinite(results[i].irradiance_w_m2, i, "irradiance_w_m2");
    requireFinite(results[i].error_estimate_w_m2, i, "error_estimate_w_m2");
  }
  requireFiniteColumns(extra, points_m.size());
  std::vector<std::string> names = {"irradiance_w_m2", "error_estimate_w_m2", "evaluations",
                                    "converged"};
  for (const CsvColumn& c : extra) names.push_back(c.name);
  // The results written as they are, not copied into columns first.
  writeRows(out, points_m, names, [&](std::string& line, std::size_t i) {
    const ObserverResult& r = results[i];
    line += ',';
    appendNumber(line, r.irradiance_w_m2);
    line += ',';
    appendNumber(line, r.error_estimate_w_m2);
    line += ',';
    line += std::to_string(static_cast<long long>(r.evaluations));
    line += r.converged ? ",1" : ",0";
    for (const CsvColumn& c : extra) {
      line += ',';
      appendValue(line, c, i);
    }
  });
}

}  // namespace glint
