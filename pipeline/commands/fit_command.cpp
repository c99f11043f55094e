#include "pipeline/commands/fit_command.h"

#include <nlohmann/json.hpp>

#include "pipeline/base/input_error.h"
#include "pipeline/base/number_format.h"
#include "pipeline/input/brdf_table_file.h"
#include "pipeline/input/scene.h"

namespace glint {
namespace {

// The fitted material as a scene's `materials.<name>` takes it.
nlohmann::json materialJson(const Material& m) {
  nlohmann::json j = nlohmann::json::object();
  if (!m.more_lobes.empty()) {
    nlohmann::json lobes = nlohmann::json::array();
    lobes.push_back({{"reflectance", m.specular_reflectance}, {"sigma", m.lobe.sigma}});
    for (const SpecularLobe& l : m.more_lobes)
      lobes.push_back({{"reflectance", l.reflectance}, {"sigma", l.shape.sigma}});
    j["lobes"] = lobes;
  } else if (m.specular_reflectance > 0.0) {
    j["specular_reflectance"] = m.specular_reflectance;
    j["sigma"] = m.lobe.sigma;
  }
  if (m.abg) j["abg"] = {{"a_per_sr", m.abg->a_per_sr}, {"b", m.abg->b}, {"g", m.abg->g}};
  if (m.diffuse_reflectance > 0.0) j["diffuse_reflectance"] = m.diffuse_reflectance;
  return j;
}

// The material as printed, read back by the scene reader in a scene of one sphere: whatever it
// refuses, the fit must not print as a material to use.
void requireASceneTakes(const nlohmann::json& material, const std::string& table_path) {
  const nlohmann::json scene = {
      {"laser",
       {{"position", {-10, 0, 0}},
        {"direction", {1, 0, 0}},
        {"power_w", 1.0},
        {"wavelength_nm", 532},
        {"beam", {{"profile", "flat_top"}, {"radius_m", 1.0}}}}},
      {"materials", {{"fitted", material}}},
      {"objects",
       {{{"shape", "sphere"}, {"center", {0, 0, 0}}, {"radius", 0.5}, {"material", "fitted"}}}}};
  try {
    (void)parseScene(scene.dump(), "the fit");
  } catch (const InputError& e) {
    throw InputError(
        table_path + ": the fitted material is not one a scene takes (" + e.what() +
        "); fit fewer terms (--lobes, --no-abg, --no-diffuse), or check the table's scale");
  }
}

// Above this, the fit misses the table by more than a hazard analysis may carry where the light
// is: the table itself (`"table"`) is then the material to use.
constexpr double kWarnRelativeError = 0.1;

}  // namespace

void runFit(const FitArgs& args, std::ostream& out, std::ostream& err) {
  if (args.model.lobes < 0 || args.model.lobes > 4)
    throw InputError("--lobes must be 0 to 4, not " + std::to_string(args.model.lobes));
  if (args.model.lobes == 0 && !args.model.abg && !args.model.diffuse)
    throw InputError("nothing to fit: give --lobes, or leave ABg or the Lambertian part in");
  const auto table = readBrdfTable(args.table_path);
  const MaterialFit fit = fitMaterial(*table, args.model);
  if (fit.nodes < static_cast<std::size_t>(fit.parameters)) {
    throw InputError(args.table_path + ": " + std::to_string(fit.nodes) +
                     " node(s) below 89.5° of θ cannot settle the fit's " +
                     std::to_string(fit.parameters) +
                     " parameters: give a table of more nodes, or fit fewer terms");
  }
  const nlohmann::json material = materialJson(fit.material);
  requireASceneTakes(material, args.table_path);
  const BrdfTable::Reflectance albedo = table->maxHemisphericalReflectance();
  const nlohmann::json j = {{"table", args.table_path},
                            {"material", material},
                            {"fit",
                             {{"nodes", fit.nodes},
                              {"parameters", fit.parameters},
                              {"rms_log_error", fit.rms_log_error},
                              {"max_relative_error", fit.max_relative_error},
                              {"energy", fit.energy},
                              {"dropped", fit.dropped},
                              {"table_max_hemispherical_reflectance", albedo.value}}}};
  out << j.dump(2) << "\n";
  for (const std::string& d : fit.dropped) {
    err << "glint fit: note: left out " << d << ": the fit drove it to nothing\n";
  }
  if (!(fit.max_relative_error <= kWarnRelativeError)) {
    err << "glint fit: warning: the fit is up to " << formatNumber("%.3g", fit.max_relative_error)
        << " (relative) off the table where the light is (nodes at least 1 % of its peak): a "
           "scene of it may read the light that far from the table, short of it as well as "
           "over; fit more terms, or give the table itself as the material's \"table\"\n";
  }
}

}  // namespace glint
