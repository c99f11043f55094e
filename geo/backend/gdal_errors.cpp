#include "geo/backend/gdal_errors.h"

#include <cpl_error.h>
#include <gdal.h>

#include <mutex>

#include "geo/backend.h"

namespace glint::detail {
namespace {}  // namespace

GdalErrors::GdalErrors() {
  static std::once_flag once;
  std::call_once(once, [] {
    GDALAllRegister();
    keepGdalOffline();
    // GDAL's block cache defaults to 5 % of the machine's memory (1.2 GB here), outside what
    // --memory counts: a footprint's GeoTIFF of 64 M pixels filled it while written, and a run
    // estimated at 1 GB was stopped at 1.9 GB. Blocks past this are written out, not held.
    GDALSetCacheMax64(kGdalBlockCacheBytes);
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
