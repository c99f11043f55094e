// GeoTIFF and GeoJSON/KML through GDAL, written into its memory file system and handed back
// as bytes: glint's outputs go through its own atomic files.
#include <cpl_conv.h>
#include <cpl_string.h>
#include <cpl_vsi.h>
#include <gdal_alg.h>
#include <gdal_priv.h>
#include <ogr_spatialref.h>
#include <ogrsf_frmts.h>
#include <unistd.h>

#include <atomic>
#include <cmath>
#include <memory>
#include <stdexcept>

#include "geo/backend/gdal_errors.h"
#include "geo/backend/parts.h"

namespace glint {
namespace {

using detail::GdalErrors;

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error(GdalErrors::explain(what));
}

// A file in GDAL's memory file system, unique to this process and call.
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

  // The closed file's bytes.
  [[nodiscard]] std::string bytes() const {
    vsi_l_offset length = 0;
    GByte* data = VSIGetMemFileBuffer(path_.c_str(), &length, FALSE);
    if (data == nullptr) fail("GDAL wrote no file");
    return {reinterpret_cast<const char*>(data), static_cast<std::size_t>(length)};
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

OGRSpatialReference mapReference(const GeoRaster& r) {
  OGRSpatialReference srs;
  const OGRErr err =
      r.epsg > 0 ? srs.importFromEPSG(r.epsg) : srs.importFromProj4(r.map_proj.c_str());
  if (err != OGRERR_NONE) fail("GDAL does not know the map's coordinate system " + r.map_proj);
  srs.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  return srs;
}

}  // namespace

std::string gdalGeoTiff(const GeoRaster& r) {
  const GdalErrors quiet;
  const MemoryFile file(".tif");
  {
    char** options = CSLSetNameValue(nullptr, "COMPRESS", "DEFLATE");
    options = CSLSetNameValue(options, "TILED", "YES");
    Dataset d = create("GTiff", file.path(), r.width, r.height, static_cast<int>(r.bands.size()),
                       GDT_Float32, options);
    CSLDestroy(options);
    std::array<double, 6> gt = r.geotransform;
    const OGRSpatialReference srs = mapReference(r);
    if (d->SetGeoTransform(gt.data()) != CE_None || d->SetSpatialRef(&srs) != CE_None)
      fail("GDAL cannot geo-reference the map");
    for (const auto& [key, value] : r.metadata) d->SetMetadataItem(key.c_str(), value.c_str());
    for (std::size_t b = 0; b < r.bands.size(); ++b) {
      GDALRasterBand* band = d->GetRasterBand(static_cast<int>(b) + 1);
      band->SetDescription(r.band_names[b].c_str());
      band->SetUnitType(r.band_units[b].c_str());
      if (band->RasterIO(GF_Write, 0, 0, r.width, r.height, const_cast<float*>(r.bands[b]->data()),
                         r.width, r.height, GDT_Float32, 0, 0) != CE_None)
        fail("GDAL cannot write the band " + r.band_names[b]);
    }
  }
  return file.bytes();
}

std::string gdalZones(const GeoZones& z) {
  const GdalErrors quiet;
  const GeoRaster& g = z.grid;
  OGRSpatialReference map_srs = mapReference(g);
  OGRSpatialReference wgs84;
  wgs84.SetWellKnownGeogCS("WGS84");
  wgs84.SetAxisMappingStrategy(OAMS_TRADITIONAL_GIS_ORDER);
  std::unique_ptr<OGRCoordinateTransformation> to_wgs84(
      OGRCreateCoordinateTransformation(&map_srs, &wgs84));
  if (!to_wgs84) fail("GDAL cannot convert the map to WGS 84");

  // The mask raster and the polygons in the map's coordinates, in memory.
  Dataset mask = create("MEM", "", g.width, g.height, 1, GDT_Byte);
  std::array<double, 6> gt = g.geotransform;
  const double map_pixel_m2 = std::abs(gt[1] * gt[5] - gt[2] * gt[4]);
  mask->SetGeoTransform(gt.data());
  mask->SetSpatialRef(&map_srs);
  Dataset shapes = create("Memory", "", 0, 0, 0, GDT_Unknown);
  OGRLayer* polygons = shapes->CreateLayer("polygons", &map_srs, wkbPolygon, nullptr);
  if (polygons == nullptr) fail("GDAL cannot make a polygon layer");
  OGRFieldDefn value("value", OFTInteger);
  if (polygons->CreateField(&value) != OGRERR_NONE) fail("GDAL cannot make a polygon field");

  const MemoryFile file(z.kml ? ".kml" : ".geojson");
  {
    // KML names each placemark by its kind, as Google Earth lists them.
    char** options = z.kml ? CSLSetNameValue(nullptr, "NameField", "kind") : nullptr;
    Dataset d = create(z.kml ? "KML" : "GeoJSON", file.path(), 0, 0, 0, GDT_Unknown, options);
    CSLDestroy(options);
    // 9 decimals of a degree: 0.1 mm, finer than any pixel (RFC 7946's default 7 is 1 cm).
    char** layer_options = z.kml ? nullptr
                                 : CSLSetNameValue(CSLSetNameValue(nullptr, "RFC7946", "YES"),
                                                   "COORDINATE_PRECISION", "9");
    OGRLayer* layer = d->CreateLayer(z.layer_name.c_str(), &wgs84, wkbPolygon, layer_options);
    CSLDestroy(layer_options);
    if (layer == nullptr) fail("GDAL cannot make the zones' layer");
    std::vector<std::string> fields = {"kind", "description"};
    for (const auto& [key, v] : z.properties) fields.push_back(key);
    for (const std::string& name : fields) {
      OGRFieldDefn f(name.c_str(), OFTString);
      if (layer->CreateField(&f) != OGRERR_NONE) fail("GDAL cannot make the field " + name);
    }
    OGRFieldDefn area("area_m2", OFTReal);
    if (layer->CreateField(&area) != OGRERR_NONE) fail("GDAL cannot make the field area_m2");

    GDALRasterBand* band = mask->GetRasterBand(1);
    const std::unique_ptr<char*, void (*)(char**)> wrap_options(
        CSLSetNameValue(nullptr, "WRAPDATELINE", "YES"), CSLDestroy);
    char** wrap = wrap_options.get();
    const OGRGeometryFactory::TransformWithOptionsCache cache;
    for (const GeoZones::Zone& zone : z.zones) {
      if (band->RasterIO(GF_Write, 0, 0, g.width, g.height,
                         const_cast<std::uint8_t*>(zone.inside.data()), g.width, g.height, GDT_Byte,
                         0, 0) != CE_None)
        fail("GDAL cannot hold the zone " + zone.kind);
      // Pixels outside the zone are the band's own mask (0): only the zone's become polygons.
      if (GDALPolygonize(band, band, OGRLayer::ToHandle(polygons), 0, nullptr, nullptr, nullptr) !=
          CE_None)
        fail("GDAL cannot outline the zone " + zone.kind);
      polygons->ResetReading();
      std::vector<GIntBig> ids;
      for (auto& shape : *polygons) {
        ids.push_back(shape->GetFID());
        std::unique_ptr<OGRGeometry> geometry(shape->GetGeometryRef()->clone());
        // The plane's own area: the map's, in pixels, times the plane's pixel (the map shrinks
        // a plane above the ellipsoid and scales by the projection's factor).
        const double area_m2 = geometry->toPolygon()->get_Area() / map_pixel_m2 * z.pixel_area_m2;
        // A zone across the antimeridian is cut there into the pieces on either side (RFC 7946
        // §3.1.9, and KML alike): one ring from 179.9° to −179.9° would run the long way round.
        std::unique_ptr<OGRGeometry> on_earth(
            OGRGeometryFactory::transformWithOptions(geometry.get(), to_wgs84.get(), wrap, cache));
        if (!on_earth) fail("GDAL cannot carry a zone's outline to WGS 84");
        OGRFeature feature(layer->GetLayerDefn());
        feature.SetField("kind", zone.kind.c_str());
        feature.SetField("description", zone.description.c_str());
        for (const auto& [key, v] : z.properties) feature.SetField(key.c_str(), v.c_str());
        feature.SetField("area_m2", area_m2);
        feature.SetGeometryDirectly(on_earth.release());
        feature.SetStyleString(zone.kind == "hazardous" ? "BRUSH(fc:#FF000080);PEN(c:#FF0000)"
                                                        : "BRUSH(fc:#FFA50080);PEN(c:#FFA500)");
        if (layer->CreateFeature(&feature) != OGRERR_NONE) fail("GDAL cannot write a zone");
      }
      // The next zone's polygons start from an empty layer.
      for (GIntBig id : ids) {
        if (polygons->DeleteFeature(id) != OGRERR_NONE) fail("GDAL cannot clear a zone's shapes");
      }
    }
  }
  return file.bytes();
}

}  // namespace glint
