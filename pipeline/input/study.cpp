#include "pipeline/input/study.h"

#include <algorithm>
#include <cmath>
#include <memory>

#include "pipeline/base/number_format.h"
#include "pipeline/input/json_reader.h"

namespace glint {
namespace {

// Enough for any study a cluster finishes; beyond it a misplaced "count" is the likelier cause.
constexpr std::size_t kMaxScenarios = 1'000'000;

// The values of a sweep: an array of numbers, or {"from", "to", "count"} evenly spaced.
std::vector<double> readValues(ObjectReader& r, const std::string& key) {
  const json& v = r.require(key);
  std::vector<double> out;
  if (v.is_array()) {
    for (const json& x : v) {
      if (!x.is_number() || !std::isfinite(x.get<double>()))
        r.fail(key, "must be an array of finite numbers or {\"from\", \"to\", \"count\"}");
      out.push_back(x.get<double>());
    }
  } else if (v.is_object()) {
    ObjectReader range(v, r.at(key), r.source());
    const double from = range.number("from");
    const double to = range.number("to");
    const std::int64_t count = range.integer("count", 0);
    if (count < 1 || count > 100000) range.fail("count", "must be an integer in [1, 100000]");
    range.finish();
    for (std::int64_t i = 0; i < count; ++i) {
      out.push_back(count == 1 ? from
                               : from + (to - from) * static_cast<double>(i) /
                                            static_cast<double>(count - 1));
    }
  } else {
    r.fail(key, "must be an array of numbers or {\"from\", \"to\", \"count\"}");
  }
  if (out.empty()) r.fail(key, "must hold at least one value");
  return out;
}

std::vector<double> readAngles(ObjectReader& r, const std::string& key) {
  if (!r.has(key)) return {0.0};
  std::vector<double> out = readValues(r, key);
  for (double a : out) {
    if (!(std::abs(a) <= 360.0)) r.fail(key, "angles must be in [-360, 360] degrees");
  }
  return out;
}

Pose readPose(ObjectReader r) {
  const PoseKey key = readPoseKey(std::move(r));
  return {key.time_s, key.offset_m, key.angles_deg[0], key.angles_deg[1], key.angles_deg[2]};
}

// The trajectory's poses, and with `step_s` the poses between them every step_s (linear in
// offset and angles).
std::vector<Pose> readTrajectory(ObjectReader r) {
  const json& list = r.require("poses");
  if (!list.is_array() || list.empty()) r.fail("poses", "must be a non-empty array of poses");
  std::vector<Pose> keys;
  for (std::size_t i = 0; i < list.size(); ++i) {
    keys.push_back(
        readPose(ObjectReader(list[i], r.at("poses") + "/" + std::to_string(i), r.source())));
    if (i > 0 && !(keys[i].time_s > keys[i - 1].time_s))
      r.fail("poses", "times must increase from pose to pose (pose " + std::to_string(i) + ")");
  }
  const std::optional<double> step = r.optionalNumber("step_s");
  r.finish();
  if (!step) return keys;
  const double span = keys.back().time_s - keys.front().time_s;
  if (!(*step > 0.0) || span / *step > static_cast<double>(kMaxScenarios))
    r.fail("step_s", "must be > 0 and give at most 1 000 000 poses");
  std::vector<Pose> out;
  const auto steps = static_cast<std::size_t>(std::floor(span / *step * (1.0 + 1e-12)));
  std::size_t seg = 0;
  for (std::size_t s = 0; s <= steps; ++s) {
    const double t = keys.front().time_s + static_cast<double>(s) * *step;
    while (seg + 2 < keys.size() && t > keys[seg + 1].time_s) ++seg;
    const Pose& a = keys[seg];
    const Pose& b = keys[std::min(seg + 1, keys.size() - 1)];
    const double w =
        b.time_s > a.time_s ? std::clamp((t - a.time_s) / (b.time_s - a.time_s), 0.0, 1.0) : 0.0;
    auto mix = [w](double x, double y) { return x + w * (y - x); };
    out.push_back({t, a.offset_m + w * (b.offset_m - a.offset_m), mix(a.yaw_deg, b.yaw_deg),
                   mix(a.pitch_deg, b.pitch_deg), mix(a.roll_deg, b.roll_deg)});
  }
  // The last key pose belongs to the trajectory even when step_s does not land on it.
  if (out.back().time_s < keys.back().time_s - 1e-9 * std::max(1.0, span))
    out.push_back(keys.back());
  return out;
}

// SplitMix64 (Steele, Lea, Flood 2014): a fully specified generator, so a seed gives the same
// jitter on every platform and standard library (std::normal_distribution does not promise that).
std::uint64_t splitMix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9e3779b97f4a7c15ull);
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
  return z ^ (z >> 31);
}

// A uniform double in (0, 1]: 53 random bits, never 0 (Box–Muller takes its log).
double uniform01(std::uint64_t& state) {
  return (static_cast<double>(splitMix64(state) >> 11) + 1.0) * 0x1.0p-53;
}

// Jitter sample k: two independent N(0, σ²) angles by Box–Muller, from a stream that depends on
// (seed, k) alone, so sample k is the same in every combination of the other parameters.
std::pair<double, double> jitterAngles(std::uint64_t seed, int k, double sigma_rad) {
  std::uint64_t state = seed ^ (0xd1b54a32d192ed03ull * (static_cast<std::uint64_t>(k) + 1));
  splitMix64(state);  // decorrelates neighbouring seeds
  const double r = std::sqrt(-2.0 * std::log(uniform01(state)));
  const double phi = 2.0 * kPi * uniform01(state);
  return {sigma_rad * r * std::cos(phi), sigma_rad * r * std::sin(phi)};
}

json vecJson(const Vec3& v) { return json::array({v.x, v.y, v.z}); }

// The scenario's own angles first, then its pose's.
glm::dquat scenarioTurn(const Scenario& s) {
  return yawPitchRoll(s.pose.yaw_deg, s.pose.pitch_deg, s.pose.roll_deg) *
         yawPitchRoll(s.yaw_deg, s.pitch_deg, s.roll_deg);
}

Vec3 scenarioCentre(const Study& study, const Scenario& s, const glm::dquat& turn,
                    const ObjectSpec& base) {
  return study.pivot_m + s.pose.offset_m + turn * (base.centre_m() - study.pivot_m);
}

// The laser's direction d with the pointing error of Scenario::jitter_u_rad, jitter_v_rad, not
// normalised: the scene normalises it once, as its reader does the file's vector, so that the
// scene in memory and the one its file gives agree to the last bit.
Vec3 jitteredDirection(const Vec3& d, const Scenario& s) {
  const Vec3 eu = anyPerpendicular(d);
  const Vec3 ev = glm::cross(d, eu);
  return d + std::tan(s.jitter_u_rad) * eu + std::tan(s.jitter_v_rad) * ev;
}

std::string scenarioDescription(const Study& study, const Scenario& s) {
  const std::string what = "scenario " + std::to_string(s.index) + " of " + study.source;
  const std::string& base = study.base.description;
  return base.empty() ? what : base + " [" + what + "]";
}

// A mesh's triangles turned by @p turn about its frame's origin (the object's centre).
std::shared_ptr<const TriangleMesh> turnedMesh(const TriangleMesh& mesh, const glm::dquat& turn) {
  auto out = std::make_shared<TriangleMesh>(mesh);
  for (Vec3& p : out->positions_m) p = turn * p;
  // A zero normal (none given, none filled) stays zero, as the scene reader leaves it.
  for (Vec3& n : out->normals) n = tryNormalize(turn * n).value_or(Vec3(0.0));
  return out;
}

// The base scene with the scenario's changes, made in memory: the meshes the base scene loaded
// are turned, never read again. Without @p turn_meshes the meshes stay as loaded (enough to
// check the scenario's values, for every scenario before any work).
Scene applyScenario(const Study& study, const Scenario& s, bool turn_meshes) {
  Scene scene = study.base;
  scene.source = study.source + " scenario " + std::to_string(s.index);
  scene.description = scenarioDescription(study, s);
  const glm::dquat turn = scenarioTurn(s);
  const bool turned = turn != glm::dquat(1.0, 0.0, 0.0, 0.0);
  for (ObjectSpec& o : scene.objects) {
    const Vec3 centre_m = scenarioCentre(study, s, turn, o);
    if (MeshSpec* mesh = o.mesh()) {
      mesh->transform.translation_m = centre_m;
      mesh->transform.rotation = turn * mesh->transform.rotation;
      if (turned && turn_meshes) mesh->mesh = turnedMesh(*mesh->mesh, turn);
    } else {
      o.shape = placed(*o.analytic(), centre_m, turn);
    }
  }
  for (std::size_t i = 0; i < scene.materials.size(); ++i) {
    if (!study.material.empty() && scene.material_names[i] != study.material) continue;
    Material& m = scene.materials[i];
    if (s.surface_state) {
      m = study.base.materials[*s.surface_state];
      scene.material_table_files[i] = study.base.material_table_files[*s.surface_state];
    }
    if (s.sigma) m.lobe.sigma = *s.sigma;
    if (s.specular_reflectance) m.specular_reflectance = *s.specular_reflectance;
  }
  if (s.jitter_sample >= 0) {
    scene.laser.direction = *tryNormalize(jitteredDirection(study.base.laser.direction, s));
  }
  recheckScene(scene);
  return scene;
}

// The base scene named by `scene`, relative to the study file; its errors are the study's, at
// its key.
void readBaseScene(ObjectReader& r, Study& study, const std::filesystem::path& dir,
                   std::uint64_t memory_budget_bytes) {
  const std::string scene_name = r.string("scene");
  study.scene_path = dir / scene_name;
  try {
    study.scene_text = readUserFile(study.scene_path, "scene file");
    study.base = parseScene(study.scene_text, study.scene_path.string(), std::nullopt, {},
                            memory_budget_bytes);
    if (study.base.engagement) {
      // Each scenario is the engagement integrated over the scene's box and planes, as glint
      // run integrates it: the far field and the reach judge one pose.
      study.base.far_field.enabled = false;
      study.base.reach.enabled = false;
    }
  } catch (const InputError& e) {
    throw InputError(study.source + ": /scene: " + e.what());
  }
}

// A base scene a study cannot vary: nothing to map, or a study key its engagement overrules.
void checkBaseSceneFitsStudy(ObjectReader& r, const Study& study) {
  if (!study.base.observers && study.base.planes.empty()) {
    r.fail("scene", "the scene has no observer box or planes: a study needs one");
  }
  const bool engagement = study.base.engagement.has_value();
  if (engagement && r.has("trajectory")) {
    r.fail("trajectory",
           "the scene is an engagement, which moves the target itself: give its poses in the "
           "scene's engagement.target.poses");
  }
  if (engagement && r.has("pointing_jitter") &&
      study.base.engagement->motion.pointing == LaserPointing::Keyed) {
    r.fail("pointing_jitter",
           "the engagement's laser follows keyed directions, which the jitter of the scene's "
           "laser.direction would not move: give jitter with pointing fixed or track");
  }
  if (study.base.wantsReach() && !study.base.far_field.enabled) {
    r.fail("scene", "the scene asks for the hazard reach without the far field it ends in");
  }
}

Vec3 readPivot(ObjectReader& r, const Scene& base) {
  Vec3 sum(0.0);
  for (const ObjectSpec& o : base.objects) sum += o.centre_m();
  return r.has("pivot") ? r.vec3("pivot") : sum / static_cast<double>(base.objects.size());
}

// The values each swept parameter takes; an unswept one has a single value (no σ or
// reflectance: the scene's own).
struct SweepAxes {
  std::vector<double> yaw{0.0}, pitch{0.0}, roll{0.0};
  std::vector<std::optional<double>> sigma{std::nullopt}, reflectance{std::nullopt};
  std::vector<std::optional<std::size_t>> surface_state{std::nullopt};
};

std::vector<std::optional<double>> readSweptSigmas(ObjectReader& s) {
  std::vector<std::optional<double>> out;
  for (double x : readValues(s, "sigma")) {
    if (!(x > 0.0)) s.fail("sigma", "values must be > 0");
    out.emplace_back(x);
  }
  return out;
}

std::vector<std::optional<double>> readSweptReflectances(ObjectReader& s) {
  std::vector<std::optional<double>> out;
  for (double x : readValues(s, "specular_reflectance")) {
    if (!(x >= 0.0 && x <= 1.0)) s.fail("specular_reflectance", "values must be in [0, 1]");
    out.emplace_back(x);
  }
  return out;
}

// The key `surface_state`: names of the base scene's materials, each in turn the swept one.
std::vector<std::optional<std::size_t>> readSurfaceStates(ObjectReader& s, const Scene& base) {
  const json& list = s.raw().at("surface_state");
  if (!list.is_array() || list.empty())
    s.fail("surface_state", "must be a list of the scene's material names");
  std::vector<std::optional<std::size_t>> out;
  for (const json& name : list) {
    const auto at = name.is_string() ? std::find(base.material_names.begin(),
                                                 base.material_names.end(), name.get<std::string>())
                                     : base.material_names.end();
    if (at == base.material_names.end()) {
      s.fail("surface_state", "each must name a material of the scene, not " + name.dump());
    }
    out.emplace_back(static_cast<std::size_t>(at - base.material_names.begin()));
  }
  return out;
}

// Sets study.material, the material the σ, reflectance and surface-state sweeps change.
SweepAxes readSweep(ObjectReader s, Study& study) {
  SweepAxes axes;
  axes.yaw = readAngles(s, "yaw_deg");
  axes.pitch = readAngles(s, "pitch_deg");
  axes.roll = readAngles(s, "roll_deg");
  if (s.has("sigma")) axes.sigma = readSweptSigmas(s);
  if (s.has("specular_reflectance")) axes.reflectance = readSweptReflectances(s);
  if (s.has("surface_state")) axes.surface_state = readSurfaceStates(s, study.base);
  study.material = s.string("material", "");
  if (!study.material.empty()) {
    const std::vector<std::string>& names = study.base.material_names;
    if (std::find(names.begin(), names.end(), study.material) == names.end())
      s.fail("material", "the scene has no material \"" + study.material + "\"");
  }
  s.finish();
  return axes;
}

// Sets the study's jitter and its rounds; returns the jitter samples scenarios are made for.
int readPointingJitter(ObjectReader j, Study& study) {
  int jitter_samples = 0;
  study.jitter_sigma_rad = j.number("sigma_rad");
  if (!(study.jitter_sigma_rad >= 0.0 && study.jitter_sigma_rad <= 0.1))
    j.fail("sigma_rad", "must be in [0, 0.1] rad (a pointing error, not a new direction)");
  if (j.has("precision") == j.has("samples"))
    j.fail("samples", "give either `samples` or a `precision` to stop at");
  if (j.has("samples")) {
    const std::int64_t n = j.integer("samples", 0);
    if (n < 1 || n > 100000) j.fail("samples", "must be an integer in [1, 100000]");
    jitter_samples = static_cast<int>(n);
  } else {
    const double h = j.number("precision");
    if (!(h >= 0.005 && h <= 0.5))
      j.fail("precision", "must be in [0.005, 0.5]: the half-width of a point's interval");
    study.precision_half_width = h;
    const std::int64_t n = j.integer("max_samples", 4096);
    if (n < 1 || n > 100000) j.fail("max_samples", "must be an integer in [1, 100000]");
    jitter_samples = static_cast<int>(n);
    study.first_round_samples = std::min(study.first_round_samples, jitter_samples);
  }
  study.max_samples = jitter_samples;
  const std::int64_t seed = j.integer("seed", 1);
  if (seed < 0) j.fail("seed", "must be an integer ≥ 0");
  study.jitter_seed = static_cast<std::uint64_t>(seed);
  j.finish();
  return jitter_samples;
}

void readCoverage(ObjectReader c, Study& study) {
  study.coverage_confidence = c.number("confidence", study.coverage_confidence);
  if (!(study.coverage_confidence >= 0.5 && study.coverage_confidence < 1.0))
    c.fail("confidence", "must be in [0.5, 1)");
  study.coverage_probability = c.number("probability", study.coverage_probability);
  if (!(study.coverage_probability > 0.0 && study.coverage_probability <= 1.0))
    c.fail("probability", "must be in (0, 1]");
  c.finish();
}

// Counted in doubles, before any scenario is made: a product of sizes can overflow.
void checkScenarioCount(const std::string& source, std::size_t poses, const SweepAxes& axes,
                        int jitter_samples) {
  const double count =
      static_cast<double>(poses) * static_cast<double>(axes.yaw.size()) *
      static_cast<double>(axes.pitch.size()) * static_cast<double>(axes.roll.size()) *
      static_cast<double>(axes.surface_state.size()) * static_cast<double>(axes.sigma.size()) *
      static_cast<double>(axes.reflectance.size()) * std::max(1, jitter_samples);
  if (count > static_cast<double>(kMaxScenarios)) {
    throw InputError(source + ": " + formatNumber("%.4g", count) +
                     " scenarios: at most 1 000 000 (split the study)");
  }
}

// Nested in this order, the jitter (added by addScenarios()) innermost.
std::vector<Scenario> sweepCombinations(const std::vector<Pose>& poses, const SweepAxes& axes) {
  std::vector<Scenario> combinations;
  for (const Pose& pose : poses)
    for (double y : axes.yaw)
      for (double p : axes.pitch)
        for (double ro : axes.roll)
          for (const auto& state : axes.surface_state)
            for (const auto& sg : axes.sigma)
              for (const auto& re : axes.reflectance) {
                Scenario& s = combinations.emplace_back();
                s.surface_state = state;
                s.pose = pose;
                s.yaw_deg = y;
                s.pitch_deg = p;
                s.roll_deg = ro;
                s.sigma = sg;
                s.specular_reflectance = re;
              }
  return combinations;
}

// A round adds jitter samples after those already run: with the jitter innermost in the
// numbering, only a study whose sole variation is the jitter has them as its next scenarios.
void checkPrecisionVariesJitterAlone(const Study& study, std::size_t combinations) {
  if (study.precision_half_width && combinations > 1) {
    throw InputError(study.source +
                     ": /pointing_jitter/precision: a precision is for a study whose only "
                     "variation is the jitter; this one has " +
                     std::to_string(combinations) +
                     " combinations of poses, orientations and materials beside it (give "
                     "`samples`, or a study per combination)");
  }
}

// Each combination once per jitter sample, the jitter innermost; without jitter one pass with
// sample −1.
void addScenarios(Study& study, const std::vector<Scenario>& combinations, int jitter_samples) {
  const int first_sample = jitter_samples > 0 ? 0 : -1;
  const int end_sample = jitter_samples > 0 ? jitter_samples : 0;
  auto add = [&](const Scenario& combination, int k) {
    Scenario& s = study.scenarios.emplace_back(combination);
    s.index = study.scenarios.size() - 1;
    s.jitter_sample = k;
    if (k >= 0) {
      std::tie(s.jitter_u_rad, s.jitter_v_rad) =
          jitterAngles(study.jitter_seed, k, study.jitter_sigma_rad);
    }
  };
  for (const Scenario& c : combinations)
    for (int k = first_sample; k < end_sample; ++k) add(c, k);
}

}  // namespace

Vec3 rotateYawPitchRoll(const Vec3& v, double yaw_deg, double pitch_deg, double roll_deg) {
  return yawPitchRoll(yaw_deg, pitch_deg, roll_deg) * v;
}

Study parseStudy(std::string_view text, const std::string& source, const std::filesystem::path& dir,
                 std::uint64_t memory_budget_bytes) {
  const json root = parseJson(text, source);
  Study study;
  study.source = source;
  ObjectReader r(root, "", source);
  study.description = r.string("description", "");
  readBaseScene(r, study, dir, memory_budget_bytes);
  checkBaseSceneFitsStudy(r, study);
  study.pivot_m = readPivot(r, study.base);

  SweepAxes axes;
  if (r.has("sweep")) axes = readSweep(r.object("sweep"), study);
  int jitter_samples = 0;
  if (r.has("pointing_jitter"))
    jitter_samples = readPointingJitter(r.object("pointing_jitter"), study);
  if (r.has("coverage")) readCoverage(r.object("coverage"), study);
  std::vector<Pose> poses{Pose{}};
  if (r.has("trajectory")) poses = readTrajectory(r.object("trajectory"));
  r.finish();

  checkScenarioCount(source, poses.size(), axes, jitter_samples);
  const std::vector<Scenario> combinations = sweepCombinations(poses, axes);
  study.scenarios_per_sample = combinations.size();
  checkPrecisionVariesJitterAlone(study, combinations.size());
  addScenarios(study, combinations, jitter_samples);
  study.fnv1a64 = fnv1a64Hex(std::string(text) + '\0' + study.scene_text);
  for (const Scenario& s : study.scenarios) (void)applyScenario(study, s, false);
  return study;
}

std::size_t jitterSharingCombinations(const Study& study) {
  return study.max_samples > 0 ? study.scenarios_per_sample : 1;
}

std::size_t combinationOf(const Study& study, const Scenario& s) {
  // The jitter is the innermost loop: scenario c × samples + k.
  return study.max_samples > 0 ? s.index / static_cast<std::size_t>(study.max_samples) : 0;
}

std::vector<std::size_t> studyRounds(const Study& study) {
  if (!study.precision_half_width) return {study.scenarios.size()};
  std::vector<std::size_t> rounds;
  for (int k = study.first_round_samples;; k = std::min(2 * k, study.max_samples)) {
    rounds.push_back(static_cast<std::size_t>(k) * study.scenarios_per_sample);
    if (k == study.max_samples) return rounds;
  }
}

Study loadStudy(const std::filesystem::path& path, std::uint64_t memory_budget_bytes) {
  return parseStudy(readUserFile(path, "study file"), path.string(), path.parent_path(),
                    memory_budget_bytes);
}

std::string scenarioSceneJson(const Study& study, const Scenario& s) {
  json scene = json::parse(study.scene_text);
  const glm::dquat turn = scenarioTurn(s);
  for (std::size_t i = 0; i < scene["objects"].size(); ++i) {
    json& o = scene["objects"][i];
    const ObjectSpec& base = study.base.objects[i];
    const Vec3 c = scenarioCentre(study, s, turn, base);
    if (const MeshSpec* mesh = base.mesh()) {
      // The mesh's frame turns with the scenario; its file is named absolutely, so that the
      // scenario's scene.json stands on its own.
      const glm::dquat q = turn * mesh->transform.rotation;
      json& t = o["transform"];
      t["translation"] = vecJson(c);
      t.erase("yaw_pitch_roll_deg");
      t["rotation"] = json::array({q.x, q.y, q.z, q.w});
      o["file"] = std::filesystem::absolute(mesh->file).lexically_normal().string();
      continue;
    }
    o["center"] = vecJson(c);
    if (const std::optional<Vec3> axis = axisOf(*base.analytic())) {
      o[axisNameOf(*base.analytic())] = vecJson(turn * *axis);
    }
  }
  // The terrain's file too is named absolutely.
  if (scene.contains("terrain")) {
    scene["terrain"]["file"] =
        std::filesystem::absolute(study.base.terrain_file).lexically_normal().string();
  }
  // A measured table's file is named absolutely, as a mesh's is.
  const json base_materials = scene["materials"];
  const auto absoluteTable = [&](json& m, std::size_t i) {
    if (m.contains("table")) {
      m["table"] =
          std::filesystem::absolute(study.base.material_table_files[i]).lexically_normal().string();
    }
  };
  const auto index = [&](const std::string& name) {
    const auto& names = study.base.material_names;
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  for (auto& [name, m] : scene["materials"].items()) {
    absoluteTable(m, index(name));
    if (!study.material.empty() && name != study.material) continue;
    if (s.surface_state) {
      m = base_materials.at(study.base.material_names[*s.surface_state]);
      absoluteTable(m, *s.surface_state);
    }
    // σ and the reflectance are the first lobe's, wherever the material lists it; a material
    // of ABg or a table alone gets a lobe that reflects nothing, as it has in memory.
    json& first = m.contains("lobes") ? m["lobes"][0] : m;
    if ((s.sigma || s.specular_reflectance) && !m.contains("lobes") &&
        !m.contains("specular_reflectance")) {
      m["specular_reflectance"] = 0.0;
      m["sigma"] = study.base.materials[s.surface_state.value_or(index(name))].lobe.sigma;
    }
    if (s.sigma) first["sigma"] = *s.sigma;
    if (s.specular_reflectance)
      first[m.contains("lobes") ? "reflectance" : "specular_reflectance"] = *s.specular_reflectance;
  }
  if (s.jitter_sample >= 0) {
    scene["laser"]["direction"] = vecJson(jitteredDirection(study.base.laser.direction, s));
  }
  if (study.base.engagement) {
    // The engagement turns the target about the base scene's pivot: stated, since its default
    // (the mean of the objects' centres) moves when the scenario turns them about another.
    scene["engagement"]["pivot"] = vecJson(study.base.engagement->motion.pivot_m);
  }
  scene["description"] = scenarioDescription(study, s);
  return scene.dump(2) + "\n";
}

Scene scenarioScene(const Study& study, const Scenario& s) { return applyScenario(study, s, true); }

}  // namespace glint
