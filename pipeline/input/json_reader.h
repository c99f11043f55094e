#pragma once
/// @file
/// @brief Reading the user's JSON files (scene, study) at the boundary: every error names the
/// file and the JSON pointer of the problem, duplicate and unknown keys are refused. Internal
/// to glint_pipeline; include from .cpp files only (it brings in nlohmann-json).

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

#include "facets/vec3.h"
#include "observers/motion.h"
#include "pipeline/base/edit_distance.h"
#include "pipeline/base/input_error.h"
#include "pipeline/base/limits.h"

namespace glint {

using nlohmann::json;

// JSON-pointer escaping of one reference token (RFC 6901).
inline std::string escapeToken(std::string_view key) {
  std::string out;
  for (char ch : key) {
    if (ch == '~') {
      out += "~0";
    } else if (ch == '/') {
      out += "~1";
    } else {
      out += ch;
    }
  }
  return out;
}

inline std::string joinKeys(const std::vector<std::string>& keys) {
  std::string out;
  for (const auto& k : keys) out += (out.empty() ? "" : ", ") + k;
  return out;
}

// One JSON object of the scene with its pointer. Reading a key marks it as known; finish()
// refuses every key that was not read, so a misspelt optional key never goes unnoticed.
class ObjectReader {
 public:
  ObjectReader(const json& j, std::string pointer, const std::string& source)
      : j_(j), pointer_(std::move(pointer)), source_(source) {
    if (!j_.is_object()) failHere("must be an object");
  }

  [[noreturn]] void failHere(std::string_view message) const {
    throw InputError(source_ + ": " + (pointer_.empty() ? "/" : pointer_) + ": " +
                     std::string(message));
  }
  [[noreturn]] void fail(std::string_view key, std::string_view message) const {
    throw InputError(source_ + ": " + at(key) + ": " + std::string(message));
  }
  [[nodiscard]] std::string at(std::string_view key) const {
    return pointer_ + "/" + escapeToken(key);
  }

  bool has(const std::string& key) {
    // Asked once per use (has, then require): remembered once, for the unknown-key message.
    if (std::find(known_.begin(), known_.end(), key) == known_.end()) known_.push_back(key);
    return j_.contains(key);
  }

  const json& require(const std::string& key) {
    if (!has(key)) {
      // A key given but misspelt is what is missing most often: name it.
      for (const auto& item : j_.items()) {
        if (likelyMisspelling(item.key(), key)) {
          fail(key, "missing (required); \"" + item.key() + "\" is given: a misspelling of \"" +
                        key + "\"?");
        }
      }
      fail(key, "missing (required)");
    }
    return j_.at(key);
  }

  double number(const std::string& key) { return checkedNumber(key, require(key)); }
  double number(const std::string& key, double fallback) {
    return has(key) ? checkedNumber(key, j_.at(key)) : fallback;
  }
  std::optional<double> optionalNumber(const std::string& key) {
    if (!has(key)) return std::nullopt;
    return checkedNumber(key, j_.at(key));
  }

  std::int64_t integer(const std::string& key, std::int64_t fallback) {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    if (!v.is_number_integer()) fail(key, "must be an integer");
    return v.get<std::int64_t>();
  }

  bool boolean(const std::string& key, bool fallback) {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    if (!v.is_boolean()) fail(key, "must be true or false");
    return v.get<bool>();
  }

  std::string string(const std::string& key) {
    const json& v = require(key);
    if (!v.is_string()) fail(key, "must be a string");
    return v.get<std::string>();
  }
  std::string string(const std::string& key, const std::string& fallback) {
    if (!has(key)) return fallback;
    const json& v = j_.at(key);
    if (!v.is_string()) fail(key, "must be a string");
    return v.get<std::string>();
  }

  // One of `choices`, returned as its index.
  std::size_t choice(const std::string& key, const std::vector<std::string>& choices,
                     std::optional<std::size_t> fallback = std::nullopt) {
    if (fallback && !has(key)) return *fallback;
    const std::string value = string(key);
    const auto it = std::find(choices.begin(), choices.end(), value);
    if (it == choices.end()) fail(key, "must be one of: " + joinKeys(choices));
    return static_cast<std::size_t>(it - choices.begin());
  }

  Vec3 vec3(const std::string& key) {
    const json& v = require(key);
    if (!v.is_array() || v.size() != 3) fail(key, "must be an array of 3 numbers");
    Vec3 out;
    for (int i = 0; i < 3; ++i) {
      const json& c = v[static_cast<std::size_t>(i)];
      if (!c.is_number()) fail(key, "must be an array of 3 numbers");
      out[i] = c.get<double>();
      if (!std::isfinite(out[i])) fail(key, "must be finite");
    }
    return out;
  }

  // A direction: any non-zero length, returned normalised.
  Vec3 direction(const std::string& key) {
    const Vec3 v = vec3(key);
    // [1e300, 1e300, 0] is a direction whose squared length overflows, and [1e-310, 0, 0] one
    // whose square underflows: such are scaled by their largest component first. Others are
    // not, so that a unit vector read back from a file written by glint is the same bits.
    const double largest = std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
    if (!(largest > 0.0)) fail(key, "must not be zero-length (all three components are 0)");
    const bool squares_fit = largest > 1e-150 && largest < 1e150;
    const auto unit = tryNormalize(squares_fit ? v : v / largest);
    if (!unit) fail(key, "must be a direction of finite, non-zero length");
    return *unit;
  }

  ObjectReader object(const std::string& key) {
    return ObjectReader(require(key), at(key), source_);
  }

  // Refuses keys nobody asked for.
  void finish() const {
    for (const auto& item : j_.items()) {
      if (std::find(known_.begin(), known_.end(), item.key()) == known_.end()) {
        fail(item.key(), "unknown key (expected one of: " + joinKeys(known_) + ")");
      }
    }
  }

  [[nodiscard]] const json& raw() const { return j_; }
  [[nodiscard]] const std::string& pointer() const { return pointer_; }
  [[nodiscard]] const std::string& source() const { return source_; }

 private:
  double checkedNumber(const std::string& key, const json& v) const {
    if (!v.is_number()) fail(key, "must be a number");
    const double x = v.get<double>();
    if (!std::isfinite(x)) fail(key, "must be finite");
    return x;
  }

  const json& j_;
  std::string pointer_;
  const std::string& source_;
  std::vector<std::string> known_;
};

// Range checks. A verdict is what is wrong with a value under one rule, in the words its reader
// fails with; nothing when the rule holds. A value made in memory (a study's scenario) is checked
// by the same verdicts, so that each rule is written once (recheckScene()).
using Verdict = std::optional<std::string>;

inline Verdict positiveVerdict(double x) { return x > 0.0 ? Verdict() : Verdict("must be > 0"); }
inline Verdict unitIntervalVerdict(double x) {
  return x >= 0.0 && x <= 1.0 ? Verdict() : Verdict("must be in [0, 1]");
}
// x in [lo, hi] (pipeline/base/limits.h says why these bounds), `unit` for the message.
inline Verdict inRangeVerdict(double x, double lo, double hi, const char* unit) {
  if (x >= lo && x <= hi) return std::nullopt;
  char range[96];
  std::snprintf(range, sizeof range, "must be in [%g, %g]%s%s", lo, hi, *unit ? " " : "", unit);
  return range;
}
// A position (m) within the coordinates double arithmetic carries through the chain.
inline Verdict positionVerdict(const Vec3& p) {
  for (int a = 0; a < 3; ++a) {
    if (!(std::abs(p[a]) <= limits::kMaxCoordinateM)) {
      char message[96];
      std::snprintf(message, sizeof message, "must lie within ±%g m on every axis",
                    limits::kMaxCoordinateM);
      return message;
    }
  }
  return std::nullopt;
}

// The reader's side of each verdict: the value, or the failure naming its key.
inline double positive(ObjectReader& r, const std::string& key, double x) {
  if (auto v = positiveVerdict(x)) r.fail(key, *v);
  return x;
}
inline double inRange(ObjectReader& r, const std::string& key, double x, double lo, double hi,
                      const char* unit) {
  if (auto v = inRangeVerdict(x, lo, hi, unit)) r.fail(key, *v);
  return x;
}
inline Vec3 position(ObjectReader& r, const std::string& key) {
  const Vec3 p = r.vec3(key);
  if (auto v = positionVerdict(p)) r.fail(key, *v);
  return p;
}

// A pose of the target at a time (a study's trajectory, an engagement's target): `time_s`, and
// `offset_m`, `yaw_deg`, `pitch_deg`, `roll_deg`, each 0 unless given.
inline PoseKey readPoseKey(ObjectReader r) {
  PoseKey p;
  p.time_s = r.number("time_s");
  if (r.has("offset_m")) p.offset_m = r.vec3("offset_m");
  const char* keys[] = {"yaw_deg", "pitch_deg", "roll_deg"};
  for (int i = 0; i < 3; ++i) {
    const double a = r.number(keys[i], 0.0);
    if (!(std::abs(a) <= 3600.0)) r.fail(keys[i], "must be in [-3600, 3600] degrees");
    p.angles_deg[i] = a;
  }
  r.finish();
  return p;
}

// Follows the parser through the document so errors it meets can name their JSON path, and
// refuses duplicate keys: nlohmann keeps the last of two equal keys without a word, and a scene
// that says "power_w" twice must not silently mean the second.
class PathTracker {
 public:
  explicit PathTracker(const std::string& source) : source_(source) {}

  bool onEvent(json::parse_event_t event, const json& parsed) {
    switch (event) {
      case json::parse_event_t::object_start:
        countValueInArray();
        frames_.push_back({false, {}, {}, -1});
        break;
      case json::parse_event_t::array_start:
        countValueInArray();
        frames_.push_back({true, {}, {}, -1});
        break;
      case json::parse_event_t::object_end:
      case json::parse_event_t::array_end:
        frames_.pop_back();
        break;
      case json::parse_event_t::key: {
        Frame& f = frames_.back();
        f.current_key = parsed.get<std::string>();
        if (!f.keys.insert(f.current_key).second) {
          throw InputError(source_ + ": " + path() + ": duplicate key");  // innermost is an object
        }
        break;
      }
      case json::parse_event_t::value:
        countValueInArray();
        break;
    }
    return true;
  }

  // Where the parser is: the key or element being read. Containers in an array are counted
  // when they start, scalars when they end, so in the innermost array the element being read
  // is the one after the last counted.
  [[nodiscard]] std::string path() const {
    std::string p;
    for (std::size_t i = 0; i < frames_.size(); ++i) {
      const Frame& f = frames_[i];
      const long element = f.index + (i + 1 == frames_.size() ? 1 : 0);
      p += '/';
      p += f.is_array ? std::to_string(element) : escapeToken(f.current_key);
    }
    return p.empty() ? "/" : p;
  }

 private:
  struct Frame {
    bool is_array;
    std::set<std::string> keys;
    std::string current_key;
    long index;  // of the last element counted (see path())
  };
  void countValueInArray() {
    if (!frames_.empty() && frames_.back().is_array) ++frames_.back().index;
  }

  const std::string& source_;
  std::vector<Frame> frames_;
};

/// @brief Parses JSON text, refusing duplicate keys and numbers beyond a double.
/// @throw InputError naming @p source and, where it can, the JSON pointer.
inline json parseJson(std::string_view text, const std::string& source) {
  PathTracker tracker(source);
  try {
    return json::parse(text.begin(), text.end(),
                       [&tracker](int, json::parse_event_t event, json& parsed) {
                         return tracker.onEvent(event, parsed);
                       });
  } catch (const json::parse_error& e) {
    // nlohmann's message starts with "[json.exception.parse_error.101] ": keep the rest.
    std::string what = e.what();
    if (const auto pos = what.find("] "); pos != std::string::npos) what.erase(0, pos + 2);
    throw InputError(source + ": invalid JSON: " + what);
  } catch (const json::out_of_range& e) {
    // A number beyond the range of a double (1e999): the only way JSON spells infinity.
    throw InputError(source + ": " + tracker.path() + ": must be finite");
  }
}

/// @brief The largest scene, study or result file glint reads: a scene with every object
/// written out by hand is kilobytes; meshes come in files of their own (with their limits).
inline constexpr std::uintmax_t kMaxSceneFileBytes = std::uintmax_t{64} << 20;

/// @brief The bytes of a user's file; @p what names it in messages ("scene file"). Reads at
/// most @p max_bytes, whatever the file is (a FIFO, /dev/zero), and refuses a longer one.
/// @throw InputError when it is a folder, cannot be read or is longer than @p max_bytes.
std::string readUserFile(const std::filesystem::path& path, const std::string& what,
                         std::uintmax_t max_bytes = kMaxSceneFileBytes);

/// @brief fnv1a64() of @p bytes as 16 hex digits.
std::string fnv1a64Hex(std::string_view bytes);

}  // namespace glint
