#include "pipeline/input/brdf_table_file.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <map>
#include <stdexcept>
#include <string>
#include <tuple>
#include <vector>

#include "pipeline/base/input_error.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/base/number_format.h"
#include "pipeline/input/json_reader.h"

namespace glint {
namespace {

constexpr const char* kHeader = "theta_i_deg,theta_o_deg,delta_phi_deg,brdf_per_sr";
// A table of 181 × 181 × 361 nodes (half-degree steps everywhere) is 1.2e7 values; a finer one is
// finer than any goniometer.
constexpr std::size_t kMaxNodes = 12'000'000;
constexpr std::uintmax_t kMaxTableFileBytes = std::uintmax_t{1} << 30;

std::string trimmed(std::string line) {
  if (const auto hash = line.find('#'); hash != std::string::npos) line.erase(hash);
  const auto first = line.find_first_not_of(" \t\r");
  if (first == std::string::npos) return {};
  const auto last = line.find_last_not_of(" \t\r");
  return line.substr(first, last - first + 1);
}

// The four numbers of a row, or nothing if it is not four finite numbers.
bool parseRow(const std::string& line, std::array<double, 4>& out) {
  const char* p = line.c_str();
  for (int k = 0; k < 4; ++k) {
    char* end = nullptr;
    out[k] = std::strtod(p, &end);
    if (end == p || !std::isfinite(out[k])) return false;
    p = end;
    while (*p == ' ' || *p == '\t') ++p;
    if (k < 3) {
      if (*p != ',') return false;
      ++p;
    }
  }
  return *p == '\0';
}

constexpr const char* kAxisKeys[3] = {"theta_i_deg", "theta_o_deg", "delta_phi_deg"};

// The finest step between two nodes of an axis a table may have (degrees). The integrator takes
// a table's light to vary on half its finest step, wherever that step lies (BrdfTable::widthRad()),
// and resolves it with pieces that small: at 0.05° (tests/pipeline/scene_test.cpp) a disk's
// observers converge in at most 12 800 evaluations, at 0.01° in 6.6e5, and at 0.001° they
// exhaust the pieces allowed before their first evaluation. No goniometer resolves finer.
constexpr double kMinTableStepDeg = 0.05;

// Refuses two nodes of an axis closer than kMinTableStepDeg, naming both and where each is first
// given: merging them would change the measurement, which is the analyst's to do.
template <class Rows>
void requireResolvableSteps(const std::string& name, const char* key,
                            const std::vector<double>& nodes, const Rows& rows, int axis) {
  for (std::size_t k = 1; k < nodes.size(); ++k) {
    if (nodes[k] - nodes[k - 1] >= kMinTableStepDeg) continue;
    const auto firstLine = [&](double node) {
      for (const auto& r : rows) {
        if (r.v[static_cast<std::size_t>(axis)] == node) return r.line;
      }
      return std::size_t{0};
    };
    throw InputError(name + ": line " + std::to_string(firstLine(nodes[k])) + ": " + key + " " +
                     formatNumber("%.9g", nodes[k]) + "° lies " +
                     formatNumber("%.3g", nodes[k] - nodes[k - 1]) + "° from " +
                     formatNumber("%.9g", nodes[k - 1]) + "° (line " +
                     std::to_string(firstLine(nodes[k - 1])) + "), closer than the " +
                     formatNumber("%g", kMinTableStepDeg) +
                     "° a table may resolve: merge or drop one of them, or resample the table");
  }
}

}  // namespace

std::shared_ptr<const BrdfTable> readBrdfTable(const std::filesystem::path& path,
                                               std::uint64_t memory_budget_bytes) {
  const std::string name = path.string();
  // What a table costs is read off its size before it is read: a device or a pipe has none.
  std::error_code ec;
  const std::filesystem::file_status status = std::filesystem::status(path, ec);
  if (!ec && std::filesystem::exists(status) && !std::filesystem::is_directory(status) &&
      !std::filesystem::is_regular_file(status)) {
    throw InputError(name + ": is not a regular file; a BRDF table must be one");
  }
  const auto budget = [&](const std::string& what, std::uint64_t bytes) {
    if (memory_budget_bytes == 0) return;
    requireWithinBudget("the BRDF table " + name + " (" + what + ")", residentBytes() + bytes,
                        memory_budget_bytes, "resample the table coarser, or raise --memory");
  };
  if (!ec && std::filesystem::is_regular_file(status)) {
    budget("its text", std::filesystem::file_size(path, ec));
  }
  std::string text = readUserFile(path, "BRDF table", kMaxTableFileBytes);
  // Its rows, held beside the text while it is parsed, then the grid's values and the line of
  // each node (BrdfTable::memoryBytes() then counts the table itself).
  const auto lines = static_cast<std::uint64_t>(std::count(text.begin(), text.end(), '\n')) + 1;
  budget(std::to_string(lines) + " lines", text.size() + lines * (sizeof(double) * 5 + 8));
  struct Row {
    std::array<double, 4> v;
    std::size_t line;
  };
  std::vector<Row> rows;
  rows.reserve(static_cast<std::size_t>(std::min<std::uint64_t>(lines, kMaxNodes + 1)));
  std::size_t line_no = 0;
  bool header = false;
  std::string line;
  std::size_t start = 0;
  // A byte-order mark, as editors on Windows write one, is no part of the header.
  if (text.rfind("\xEF\xBB\xBF", 0) == 0) start = 3;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    ++line_no;
    line = trimmed(text.substr(start, end - start));
    start = end + 1;
    if (line.empty()) continue;
    line.erase(std::remove(line.begin(), line.end(), ' '), line.end());
    if (!header) {
      if (line != kHeader) {
        throw InputError(name + ": line " + std::to_string(line_no) + ": the first line must be " +
                         kHeader);
      }
      header = true;
      continue;
    }
    Row row{{}, line_no};
    if (!parseRow(line, row.v)) {
      throw InputError(name + ": line " + std::to_string(line_no) +
                       ": must be four finite numbers: θi, θo, Δφ (degrees) and the BRDF (1/sr)");
    }
    const auto& v = row.v;
    const auto where = [&](const std::string& what) {
      return InputError(name + ": line " + std::to_string(line_no) + ": " + what);
    };
    if (!(v[0] >= 0.0 && v[0] <= 90.0)) throw where("theta_i_deg must be in [0, 90]");
    if (!(v[1] >= 0.0 && v[1] <= 90.0)) throw where("theta_o_deg must be in [0, 90]");
    if (!(v[2] >= 0.0 && v[2] <= 180.0))
      throw where("delta_phi_deg must be in [0, 180] (an isotropic BRDF is even in Δφ)");
    if (!(v[3] >= 0.0)) throw where("brdf_per_sr must be ≥ 0");
    if (rows.size() >= kMaxNodes) {
      throw where("more than " + std::to_string(kMaxNodes) + " nodes; resample the table");
    }
    rows.push_back(row);
  }
  std::string().swap(text);  // the rows hold it all now
  if (!header) throw InputError(name + ": empty; the first line must be " + std::string(kHeader));
  if (rows.empty()) throw InputError(name + ": no rows after the header");

  std::array<std::vector<double>, 3> axes;
  for (int a = 0; a < 3; ++a) {
    for (const Row& r : rows) axes[a].push_back(r.v[a]);
    std::sort(axes[a].begin(), axes[a].end());
    axes[a].erase(std::unique(axes[a].begin(), axes[a].end()), axes[a].end());
    requireResolvableSteps(name, kAxisKeys[a], axes[a], rows, a);
  }
  const std::size_t n_o = axes[1].size(), n_p = axes[2].size();
  const std::size_t count = axes[0].size() * n_o * n_p;
  if (count > kMaxNodes) {
    throw InputError(name + ": its " + std::to_string(rows.size()) +
                     " rows are not a full grid: their angles span " +
                     std::to_string(axes[0].size()) + " × " + std::to_string(n_o) + " × " +
                     std::to_string(n_p) + " nodes");
  }
  const auto node = [&](const Row& r) {
    const auto index = [&](int a) {
      return static_cast<std::size_t>(std::lower_bound(axes[a].begin(), axes[a].end(), r.v[a]) -
                                      axes[a].begin());
    };
    return (index(0) * n_o + index(1)) * n_p + index(2);
  };
  // Each node once: the first node given twice, else the first missing, is named.
  std::vector<std::size_t> line_of(count, 0);
  std::vector<double> values(count, 0.0);
  for (const Row& r : rows) {
    const std::size_t k = node(r);
    if (line_of[k] != 0) {
      throw InputError(name + ": line " + std::to_string(r.line) + ": the node (" +
                       formatNumber("%g", r.v[0]) + "°, " + formatNumber("%g", r.v[1]) + "°, " +
                       formatNumber("%g", r.v[2]) + "°) is given twice (first on line " +
                       std::to_string(line_of[k]) + ")");
    }
    line_of[k] = r.line;
    values[k] = r.v[3];
  }
  for (std::size_t k = 0; k < count; ++k) {
    if (line_of[k] != 0) continue;
    const std::size_t p = k % n_p, o = (k / n_p) % n_o, i = k / (n_p * n_o);
    throw InputError(name + ": not a full grid: the node (θi " + formatNumber("%g", axes[0][i]) +
                     "°, θo " + formatNumber("%g", axes[1][o]) + "°, Δφ " +
                     formatNumber("%g", axes[2][p]) + "°) is missing (every θi, θo and Δφ the " +
                     "rows name must be given together)");
  }
  std::vector<Row>().swap(rows);  // the values and their lines say what is left to say
  std::vector<std::size_t>().swap(line_of);
  constexpr double kDeg = kPi / 180.0;
  for (auto& axis : axes) {
    for (double& x : axis) x *= kDeg;
  }
  budget(std::to_string(count) + " nodes",
         values.size() * sizeof(double) + BrdfTable::memoryBytes(axes[0], axes[1], axes[2]));
  try {
    return std::make_shared<const BrdfTable>(std::move(axes[0]), std::move(axes[1]),
                                             std::move(axes[2]), std::move(values));
  } catch (const std::invalid_argument& e) {
    throw InputError(name + ": " + e.what());
  }
}

}  // namespace glint
