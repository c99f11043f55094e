#include <dlfcn.h>

#include <filesystem>
#include <stdexcept>
#include <string>

#include "geo/backend.h"

namespace glint {

const GeoBackend& geoBackend() {
  // Loaded once, on the first scene that needs it; a failure is said each time it is asked.
  static const GeoBackend* const backend = [] {
    std::error_code ec;
    const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
    const std::filesystem::path module = exe.parent_path() / "libglint_geo_gdal.so";
    void* handle = ::dlopen(module.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (handle == nullptr) {
      const char* why = ::dlerror();
      throw std::runtime_error("glint's GDAL and PROJ module " + module.string() +
                               " cannot be loaded (it is built beside the program): " +
                               (why != nullptr ? why : "unknown reason"));
    }
    using Entry = const GeoBackend* (*)();
    const auto entry = reinterpret_cast<Entry>(::dlsym(handle, "glintGeoBackend"));
    if (entry == nullptr) throw std::runtime_error(module.string() + " is not glint's geo module");
    return entry();
  }();
  return *backend;
}

}  // namespace glint
