#include "geo/backend/gdal_errors.h"

#include <cpl_error.h>
#include <gdal.h>

#include <mutex>

namespace glint::detail {

GdalErrors::GdalErrors() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    keepGdalOffline();
  });
  CPLPushErrorHandler(CPLQuietErrorHandler);
  CPLErrorReset();
}

GdalErrors::~GdalErrors() { CPLPopErrorHandler(); }

std::string GdalErrors::explain(const std::string& what) {
  const char* gdal = CPLGetLastErrorMsg();
  return what + (gdal != nullptr && *gdal != '\0' ? std::string(": ") + gdal : std::string());
}

}  // namespace glint::detail
