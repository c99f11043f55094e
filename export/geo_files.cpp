#include "export/geo_files.h"

#include <cpl_conv.h>
#include <cpl_error.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_alg.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <mutex>

#include "export/atomic_file.h"

namespace glint {
namespace {

// GDAL's drivers, registered once; its messages kept from the terminal, turned into the one
// clear message of an OutputError instead.
void initialiseGdal() {
  static std::once_flag once;
  std::call_once(once, [] { GDALAllRegister(); });
}

struct QuietGdal {
  QuietGdal() {
    initialiseGdal();
    CPLPushErrorHandler(CPLQuietErrorHandler);
    CPLErrorReset();
  }
  ~QuietGdal() { CPLPopErrorHandler(); }
  QuietGdal(const QuietGdal&) = delete;
  QuietGdal& operator=(const QuietGdal&) = delete;
};

[[noreturn]] void fail(const std::string& what) {
  const char* gdal = CPLGetLastErrorMsg();
  throw OutputError(what + (gdal != nullptr && *gdal != '\0' ? std::string(": ") + gdal : ""));
}

// A file in GDAL's memory file system, unique to this process and call: GDAL writes by name,
// glint's outputs go through AtomicFile streams.
class MemoryFile {
 public:
  explicit MemoryFile(const char* extension) {
    static std::atomic<unsigned long> counter{0};
    path_ =
        "/vsimem/glint-" + std::to_string(::getpid()) + "-" + std::to_string(++counter) + extension;
  }
  ~MemoryFile() { VSIUnlink(path_.c_str()); }
  MemoryFile(const MemoryFile&) = delete;
  MemoryFile& operator=(const MemoryFile&) = delete;

  [[nodiscard]] const char* path() const { return path_.c_str(); }

  // Copies the closed file's bytes to @p out.
  void copyTo(std::ostream& out) const {
    vsi_l_offset length = 0;
    GByte* bytes = VSIGetMemFileBuffer(path_.c_str(), &length, FALSE);
    if (bytes == nullptr) fail("GDAL wrote no file");
    out.write(reinterpret_cast<const char*>(bytes), static_cast<std::streamsize>(length));
  }

 private:
  std::string path_;
};

struct DatasetCloser {
  void operator()(GDALDataset* d) const { GDALClose(GDALDataset::ToHandle(d)); }
};
using Dataset = std::unique_ptr<GDALDataset, DatasetCloser>;

Dataset create(const char* driver_name, const char* path, int width, int height, int bands,
               GDALDataType type, char** options = nullptr) {
  GDALDriver* driver = GetGDALDriverManager()->GetDriverByName(driver_name);
  if (driver == nullptr) fail(std::string("GDAL has no ") + driver_name + " driver");
  Dataset d(driver->Create(path, width, height, bands, type, options));
  if (!d) fail(std::string("GDAL cannot create a ") + driver_name + " file");
  return d;
}

OGRSpatialReference mapReference(const SiteFrame& site) {
  OGRSpatialReference srs;
  const OGRErr err = site.mapEpsg() > 0 ? srs.importFromEPSG(site.mapEpsg())
                                        : srs.importFromProj4(site.mapProj().c_str());
  if (err != OGRERR_NONE) fail("GDAL does not know the map's coordinate system " + site.mapName());
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

// The local point at continuous pixel coordinates (c, r): corner (0, 0) is half a pixel before
// lattice point (0, height − 1).
Vec3 pixelPoint(const PlaneGrid& g, double c, double r) {
  return g.origin_m + (c - 0.5) * g.pixel_m * g.u_axis +
         (static_cast<double>(g.height) - 0.5 - r) * g.pixel_m * g.v_axis;
}

void setMetadata(GDALMajorObject& o, const GeoInfo& info, const SiteFrame& site) {
  o.SetMetadataItem("GLINT_PROGRAM", info.program_version.c_str());
  o.SetMetadataItem("GLINT_PLANE", info.plane_name.c_str());
  o.SetMetadataItem("GLINT_MPE_RULE", info.mpe_rule.c_str());
  o.SetMetadataItem("GLINT_WAVELENGTH_NM", CPLSPrintf("%.17g", info.wavelength_nm));
  o.SetMetadataItem("GLINT_MPE_W_M2", CPLSPrintf("%.17g", info.mpe_w_m2));
  const SiteSpec& s = site.spec();
  o.SetMetadataItem("GLINT_SITE",
                    CPLSPrintf("latitude %.9f deg, longitude %.9f deg, height %.3f "
                               "m, +x bearing %.6f deg",
                               s.latitude_deg, s.longitude_deg, s.height_m, s.bearing_deg));
}

// One zone's mask in GDAL's row order.
void fillRows(std::vector<unsigned char>& rows, const PlaneGrid& g,
              const std::vector<unsigned char>& inside) {
  const auto w = static_cast<std::size_t>(g.width);
  for (int r = 0; r < g.height; ++r) {
    const auto j = static_cast<std::size_t>(g.height - 1 - r);
    std::copy_n(inside.begin() + static_cast<std::ptrdiff_t>(j * w), w,
                rows.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(r) * w));
  }
}

}  // namespace

bool mappable(const Vec3& u_axis, const Vec3& v_axis) {
  const Vec3 n = glm::normalize(glm::cross(u_axis, v_axis));
  return std::abs(n.z) >= std::cos(kMaxMapTiltDeg * 3.14159265358979323846 / 180.0) - 1e-12;
}

GeoPlacement placeOnMap(const PlaneGrid& g, const SiteFrame& site) {
  const double w = g.width, h = g.height;
  const MapPoint o = site.toMap(pixelPoint(g, 0.0, 0.0));
  const MapPoint across = site.toMap(pixelPoint(g, w, 0.0));
  const MapPoint down = site.toMap(pixelPoint(g, 0.0, h));
  GeoPlacement p;
  p.geotransform = {
      o.easting_m,  (across.easting_m - o.easting_m) / w,   (down.easting_m - o.easting_m) / h,
      o.northing_m, (across.northing_m - o.northing_m) / w, (down.northing_m - o.northing_m) / h};
  const auto& gt = p.geotransform;
  for (const auto& [c, r] : {std::pair{w, h},
                             {0.5 * w, 0.5 * h},
                             {0.5 * w, 0.0},
                             {0.0, 0.5 * h},
                             {w, 0.5 * h},
                             {0.5 * w, h}}) {
    const MapPoint exact = site.toMap(pixelPoint(g, c, r));
    const double e = gt[0] + c * gt[1] + r * gt[2], n = gt[3] + c * gt[4] + r * gt[5];
    p.affine_error_m =
        std::max(p.affine_error_m, std::hypot(e - exact.easting_m, n - exact.northing_m));
  }
  return p;
}

void writeGeoTiff(std::ostream& out, const PlaneGrid& g, const std::vector<ExrChannel>& channels,
                  const std::vector<std::string>& units, const SiteFrame& site,
                  const GeoInfo& info) {
  const QuietGdal quiet;
  const auto n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  for (const ExrChannel& c : channels) {
    if (c.values == nullptr || c.values->size() != n)
      throw std::invalid_argument("writeGeoTiff: channel " + c.name +
                                  " must hold width × height values");
  }
  const GeoPlacement placement = placeOnMap(g, site);
  const MemoryFile file(".tif");
  {
    char** options = CSLSetNameValue(nullptr, "COMPRESS", "DEFLATE");
    options = CSLSetNameValue(options, "TILED", "YES");
    Dataset d = create("GTiff", file.path(), g.width, g.height, static_cast<int>(channels.size()),
                       GDT_Float32, options);
    CSLDestroy(options);
    std::array<double, 6> gt = placement.geotransform;
    const OGRSpatialReference srs = mapReference(site);
    if (d->SetGeoTransform(gt.data()) != CE_None || d->SetSpatialRef(&srs) != CE_None)
      fail("GDAL cannot geo-reference " + info.plane_name + "'s map");
    setMetadata(*d, info, site);
    d->SetMetadataItem("GLINT_AFFINE_ERROR_M", CPLSPrintf("%.3g", placement.affine_error_m));
    d->SetMetadataItem("GLINT_ROWS",
                       "row r holds lattice row height - 1 - r, as the EXR map; each pixel the "
                       "square of side pixel_m about its lattice point, seen from above");
    std::vector<float> rows(n);
    for (std::size_t b = 0; b < channels.size(); ++b) {
      const std::vector<float>& v = *channels[b].values;
      const auto w = static_cast<std::size_t>(g.width);
      for (int r = 0; r < g.height; ++r) {
        const auto j = static_cast<std::size_t>(g.height - 1 - r);
        std::copy_n(v.begin() + static_cast<std::ptrdiff_t>(j * w), w,
                    rows.begin() + static_cast<std::ptrdiff_t>(static_cast<std::size_t>(r) * w));
      }
      GDALRasterBand* band = d->GetRasterBand(static_cast<int>(b) + 1);
      band->SetDescription(channels[b].name.c_str());
      if (b < units.size()) band->SetUnitType(units[b].c_str());
      if (band->RasterIO(GF_Write, 0, 0, g.width, g.height, rows.data(), g.width, g.height,
                         GDT_Float32, 0, 0) != CE_None)
        fail("GDAL cannot write " + info.plane_name + "'s band " + channels[b].name);
    }
  }
  file.copyTo(out);
}

void writeZones(std::ostream& out, VectorFormat format, const PlaneGrid& g,
                const std::vector<ZoneMask>& zones, const SiteFrame& site, const GeoInfo& info) {
  const QuietGdal quiet;
  const auto n = static_cast<std::size_t>(g.width) * static_cast<std::size_t>(g.height);
  const GeoPlacement placement = placeOnMap(g, site);
  OGRSpatialReference map_srs = mapReference(site);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_wgs84(
      OGRCreateCoordinateTransformation(&map_srs, &wgs84));
  if (!to_wgs84) fail("GDAL cannot convert " + site.mapName() + " to WGS 84");

  // The mask raster and the polygons in the map's coordinates, in memory.
  Dataset mask = create("MEM", "", g.width, g.height, 1, GDT_Byte);
  std::array<double, 6> gt = placement.geotransform;
  const double map_pixel_m2 = std::abs(gt[1] * gt[5] - gt[2] * gt[4]);
  mask->SetGeoTransform(gt.data());
  mask->SetSpatialRef(&map_srs);
  Dataset shapes = create("Memory", "", 0, 0, 0, GDT_Unknown);
  OGRLayer* polygons = shapes->CreateLayer("polygons", &map_srs, wkbPolygon, nullptr);
  if (polygons == nullptr) fail("GDAL cannot make a polygon layer");
  OGRFieldDefn value("value", OFTInteger);
  polygons->CreateField(&value);

  const bool json = format == VectorFormat::GeoJson;
  const MemoryFile file(json ? ".geojson" : ".kml");
  {
    // KML names each placemark by its kind, as Google Earth lists them.
    char** options = json ? nullptr : CSLSetNameValue(nullptr, "NameField", "kind");
    Dataset d = create(json ? "GeoJSON" : "KML", file.path(), 0, 0, 0, GDT_Unknown, options);
    CSLDestroy(options);
    // 9 decimals of a degree: 0.1 mm, finer than any pixel (RFC 7946's default 7 is 1 cm).
    char** layer_options = json ? CSLSetNameValue(CSLSetNameValue(nullptr, "RFC7946", "YES"),
                                                  "COORDINATE_PRECISION", "9")
                                : nullptr;
    OGRLayer* layer =
        d->CreateLayer((info.plane_name + "_zones").c_str(), &wgs84, wkbPolygon, layer_options);
    CSLDestroy(layer_options);
    if (layer == nullptr) fail("GDAL cannot make the zones' layer");
    for (const char* name : {"kind", "description", "plane", "mpe_rule"}) {
      OGRFieldDefn f(name, OFTString);
      layer->CreateField(&f);
    }
    OGRFieldDefn area("area_m2", OFTReal);
    layer->CreateField(&area);

    std::vector<unsigned char> rows(n);
    for (const ZoneMask& zone : zones) {
      if (zone.inside.size() != n)
        throw std::invalid_argument("writeZones: zone " + zone.kind +
                                    " must hold width × height values");
      fillRows(rows, g, zone.inside);
      GDALRasterBand* band = mask->GetRasterBand(1);
      if (band->RasterIO(GF_Write, 0, 0, g.width, g.height, rows.data(), g.width, g.height,
                         GDT_Byte, 0, 0) != CE_None)
        fail("GDAL cannot hold the zone " + zone.kind);
      // Pixels outside the zone are the band's own mask (0): only the zone's become polygons.
      if (GDALPolygonize(band, band, OGRLayer::ToHandle(polygons), 0, nullptr, nullptr, nullptr) !=
          CE_None)
        fail("GDAL cannot outline the zone " + zone.kind);
      polygons->ResetReading();
      for (auto& shape : *polygons) {
        std::unique_ptr<OGRGeometry> geometry(shape->GetGeometryRef()->clone());
        // The plane's own area: the map's, in pixels, times the plane's pixel (the map shrinks
        // a plane above the ellipsoid and scales by the projection's factor).
        const double area_m2 =
            geometry->toPolygon()->get_Area() / map_pixel_m2 * g.pixel_m * g.pixel_m;
        if (geometry->transform(to_wgs84.get()) != OGRERR_NONE)
          fail("GDAL cannot carry a zone's outline to WGS 84");
        OGRFeature feature(layer->GetLayerDefn());
        feature.SetField("kind", zone.kind.c_str());
        feature.SetField("description", zone.description.c_str());
        feature.SetField("plane", info.plane_name.c_str());
        feature.SetField("mpe_rule", info.mpe_rule.c_str());
        feature.SetField("area_m2", area_m2);
        feature.SetGeometryDirectly(geometry.release());
        feature.SetStyleString(zone.kind == "hazardous" ? "BRUSH(fc:#FF000080);PEN(c:#FF0000)"
                                                        : "BRUSH(fc:#FFA50080);PEN(c:#FFA500)");
        if (layer->CreateFeature(&feature) != OGRERR_NONE) fail("GDAL cannot write a zone");
      }
      // The next zone's polygons start from an empty layer.
      std::vector<GIntBig> ids;
      for (auto& shape : *polygons) ids.push_back(shape->GetFID());
      for (GIntBig id : ids) {
        if (polygons->DeleteFeature(id) != OGRERR_NONE) fail("GDAL cannot clear a zone's shapes");
      }
    }
  }
  file.copyTo(out);
}

}  // namespace glint
