#include "pipeline/commands/fit_command.h"

#include <nlohmann/json.hpp>

#include "pipeline/base/input_error.h"
#include "pipeline/base/number_format.h"
#include "pipeline/input/brdf_table_file.h"

namespace glint {
namespace {

// The fitted material as a scene's `materials.<name>` takes it.
nlohmann::json materialJson(const Material& m, const MaterialFitModel& model) {
  nlohmann::json j = nlohmann::json::object();
  if (model.lobes == 1) {
    j["specular_reflectance"] = m.specular_reflectance;
    j["sigma"] = m.lobe.sigma;
  } else if (model.lobes > 1) {
    nlohmann::json lobes = nlohmann::json::array();
    lobes.push_back({{"reflectance", m.specular_reflectance}, {"sigma", m.lobe.sigma}});
    for (const SpecularLobe& l : m.more_lobes)
      lobes.push_back({{"reflectance", l.reflectance}, {"sigma", l.shape.sigma}});
    j["lobes"] = lobes;
  }
  if (m.abg) j["abg"] = {{"a_per_sr", m.abg->a_per_sr}, {"b", m.abg->b}, {"g", m.abg->g}};
  if (model.diffuse) j["diffuse_reflectance"] = m.diffuse_reflectance;
  return j;
}

}  // namespace

void runFit(const FitArgs& args, std::ostream& out, std::ostream& err) {
  if (args.model.lobes < 0 || args.model.lobes > 4)
    throw InputError("--lobes must be 0 to 4, not " + std::to_string(args.model.lobes));
  if (args.model.lobes == 0 && !args.model.abg && !args.model.diffuse)
    throw InputError("nothing to fit: give --lobes, or leave ABg or the Lambertian part in");
  const auto table = readBrdfTable(args.table_path);
  const MaterialFit fit = fitMaterial(*table, args.model);
  const BrdfTable::Reflectance albedo = table->maxHemisphericalReflectance();
  const nlohmann::json j = {{"table", args.table_path},
                            {"material", materialJson(fit.material, args.model)},
                            {"fit",
                             {{"nodes", fit.nodes},
                              {"rms_log_error", fit.rms_log_error},
                              {"max_relative_error", fit.max_relative_error},
                              {"energy", fit.energy},
                              {"table_max_hemispherical_reflectance", albedo.value}}}};
  out << j.dump(2) << "\n";
  if (fit.energy > 1.0) {
    err << "glint fit: warning: the fit reflects " << formatNumber("%.4g", fit.energy)
        << " of the light (lobes + ABg's TIS + Lambert), more than 1: a scene refuses it; fit "
           "fewer terms or check the table's scale\n";
  }
}

}  // namespace glint
