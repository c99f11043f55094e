// GDAL kept off the network: a scene file names an elevation model, and no name in it (a URL,
// a /vsicurl/ path, a VRT whose source is one) may make glint open a connection.
#include <cpl_conv.h>
#include <cpl_http.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <cpl_vsi_virtual.h>
#include <gdal_priv.h>
#include <ogr_srs_api.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <string>
#include <string_view>
#include <vector>

#include "geo/backend/gdal_errors.h"

namespace glint::detail {
namespace {

constexpr const char* kRefusal = "glint reads no file over the network";

// Stands in for a network file system: opens nothing, finds nothing.
class RefusingFilesystem final : public VSIFilesystemHandler {
 public:
  VSIVirtualHandle* Open(const char* name, const char*, bool set_error, CSLConstList) override {
    if (set_error) CPLError(CE_Failure, CPLE_AppDefined, "%s: %s", kRefusal, name);
    errno = EACCES;
    return nullptr;
  }
  int Stat(const char*, VSIStatBufL*, int) override {
    errno = ENOENT;
    return -1;
  }
};

// Stands in for every HTTP request GDAL's drivers make (WMS, WCS, the HTTP driver, ...).
CPLHTTPResult* refuseHttp(const char* url, CSLConstList, GDALProgressFunc, void*,
                          CPLHTTPFetchWriteFunc, void*, void*) {
  auto* result = static_cast<CPLHTTPResult*>(CPLCalloc(1, sizeof(CPLHTTPResult)));
  result->nStatus = 1;
  result->pszErrBuf = CPLStrdup((std::string(kRefusal) + ": " + (url ? url : "")).c_str());
  return result;
}

// The file systems of GDAL that stay on this machine (memory, archives, stdin): every other
// prefix, those GDAL 3.6 knows (/vsicurl/, /vsis3/, /vsigs/, /vsiaz/, /vsiadls/, /vsioss/,
// /vsiswift/, /vsiwebhdfs/, their _streaming twins) and any a later GDAL adds, is refused.
constexpr std::array<std::string_view, 13> kLocal = {
    "/vsimem/",   "/vsizip/",    "/vsigzip/",           "/vsitar/",     "/vsi7z/",
    "/vsirar/",   "/vsicrypt/",  "/vsisparse/",         "/vsisubfile/", "/vsistdin/",
    "/vsistdin?", "/vsistdout/", "/vsistdout_redirect/"};

// Drivers whose datasets are services, and drivers that open a connection through a client of
// their own rather than GDAL's HTTP and file layers (databases, "PG:host=…" in a VRT's source).
constexpr std::array<const char*, 26> kNetworkDrivers = {
    "HTTP",          "WMS",        "WMTS",          "WCS",     "EEDA",      "EEDAI",
    "DAAS",          "PLMosaic",   "OGCAPI",        "NGW",     "TileDB",    "WFS",
    "OAPIF",         "CSW",        "Elasticsearch", "CouchDB", "Carto",     "PLScenes",
    "PostGISRaster", "PostgreSQL", "MySQL",         "OCI",     "GeoRaster", "MSSQLSpatial",
    "ODBC",          "MongoDBv3"};

// Puts the refusing file system in the place of @p prefix's. GDAL's InstallHandler() forgets
// the handler it replaces without freeing it (its file manager frees only those it still
// holds, at its clean-up): the replaced ones are kept here, reachable for the process's life,
// as GDAL's own would have been.
void refuse(const std::string& prefix) {
  static auto* const replaced = new std::vector<VSIFilesystemHandler*>;  // never destroyed
  replaced->push_back(VSIFileManager::GetHandler(prefix.c_str()));
  VSIFileManager::InstallHandler(prefix, new RefusingFilesystem);
}

}  // namespace

void keepGdalOffline() {
  char** prefixes = VSIGetFileSystemsPrefixes();
  for (int i = 0; prefixes != nullptr && prefixes[i] != nullptr; ++i) {
    const std::string_view prefix = prefixes[i];
    if (std::find(kLocal.begin(), kLocal.end(), prefix) == kLocal.end())
      refuse(std::string(prefix));
  }
  CSLDestroy(prefixes);
  // Those of GDAL 3.6 by name besides: "/vsicurl?" (the URL as a query, "/vsicurl?url=…") is
  // a prefix of its own that the list leaves out, and a build may list another differently.
  for (const char* prefix :
       {"/vsicurl?", "/vsicurl/", "/vsicurl_streaming/", "/vsis3/", "/vsis3_streaming/", "/vsigs/",
        "/vsigs_streaming/", "/vsiaz/", "/vsiaz_streaming/", "/vsiadls/", "/vsioss/",
        "/vsioss_streaming/", "/vsiswift/", "/vsiswift_streaming/", "/vsihdfs/", "/vsiwebhdfs/"})
    refuse(prefix);
  CPLHTTPSetFetchCallback(refuseHttp, nullptr);
  OSRSetPROJEnableNetwork(FALSE);
  GDALDriverManager* drivers = GetGDALDriverManager();
  for (const char* name : kNetworkDrivers) {
    if (GDALDriver* d = drivers->GetDriverByName(name)) {
      drivers->DeregisterDriver(d);
      GDALDestroyDriver(d);
    }
  }
}

}  // namespace glint::detail
