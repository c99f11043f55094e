#include "export/lattice_vdb.h"

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <sstream>
#include <stdexcept>

#include "export/fnv1a.h"
#include "observers/field_grids.h"

namespace glint {
namespace {

std::size_t latticeSize(const std::array<int, 3>& n) {
  return static_cast<std::size_t>(n[0]) * static_cast<std::size_t>(n[1]) *
         static_cast<std::size_t>(n[2]);
}

// The archive header: magic (8 bytes), file version, library major and minor (4 each),
// has-grid-offsets (1), then the UUID as 36 characters.
constexpr std::size_t kUuidAt = 21;
constexpr std::size_t kUuidSize = 36;

// OpenVDB gives every archive a random UUID, so two writes of the same grids differ. This one
// is derived from the file's content instead (two FNV-1a hashes of it with the UUID blanked),
// so equal aggregates are equal files, whichever ranks computed them, and different ones
// still get different identifiers.
void stampContentUuid(std::string& file) {
  if (file.size() < kUuidAt + kUuidSize) return;
  std::string uuid = file.substr(kUuidAt, kUuidSize);
  // Only what is recognisably the UUID field is replaced.
  for (std::size_t i = 0; i < kUuidSize; ++i) {
    const bool dash = i == 8 || i == 13 || i == 18 || i == 23;
    if (dash != (uuid[i] == '-') ||
        (!dash && std::isxdigit(static_cast<unsigned char>(uuid[i])) == 0))
      return;
  }
  std::fill(file.begin() + kUuidAt, file.begin() + kUuidAt + kUuidSize, '0');
  const std::uint64_t a = fnv1a64(file);
  const std::uint64_t b = fnv1a64(file, a ^ 0x9e3779b97f4a7c15ull);
  char hex[33];
  std::snprintf(hex, sizeof hex, "%016llx%016llx", static_cast<unsigned long long>(a),
                static_cast<unsigned long long>(b));
  const std::string h(hex);
  uuid = h.substr(0, 8) + "-" + h.substr(8, 4) + "-" + h.substr(12, 4) + "-" + h.substr(16, 4) +
         "-" + h.substr(20, 12);
  std::copy(uuid.begin(), uuid.end(), file.begin() + kUuidAt);
}

}  // namespace

void writeLatticeVdb(std::ostream& out, const FieldSpec& spec,
                     const std::vector<LatticeChannel>& channels, const LatticeMeta& meta) {
  openvdb::initialize();
  const auto n = spec.nodes();
  const auto transform = fieldTransform(spec);
  openvdb::GridPtrVec grids;
  for (const LatticeChannel& c : channels) {
    if (c.values == nullptr || c.values->size() != latticeSize(n))
      throw std::invalid_argument("writeLatticeVdb: " + c.name + " does not fit the lattice");
    auto grid = openvdb::FloatGrid::create(0.0f);
    grid->setName(c.name);
    grid->setGridClass(openvdb::GRID_FOG_VOLUME);
    grid->setTransform(transform->copy());
    if (!c.units.empty()) grid->insertMeta("units", openvdb::StringMetadata(c.units));
    auto acc = grid->getAccessor();
    std::size_t p = 0;
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i, ++p) {
          const float v = (*c.values)[p];
          if (v != 0.0f) acc.setValue(openvdb::Coord(i, j, k), v);
        }
    grid->pruneGrid();
    grids.push_back(grid);
  }
  openvdb::MetaMap m;
  for (const auto& [key, value] : meta.strings) m.insertMeta(key, openvdb::StringMetadata(value));
  for (const auto& [key, value] : meta.numbers) m.insertMeta(key, openvdb::DoubleMetadata(value));
  std::ostringstream bytes;
  openvdb::io::Stream(bytes).write(grids, m);
  std::string file = bytes.str();
  stampContentUuid(file);
  out.write(file.data(), static_cast<std::streamsize>(file.size()));
}

std::vector<float> readLatticeVdb(const std::string& path, const std::string& grid_name,
                                  const FieldSpec& spec) {
  openvdb::initialize();
  try {
    openvdb::io::File file(path);
    file.open(false);
    auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(file.readGrid(grid_name));
    file.close();
    if (!grid) throw std::runtime_error(path + ": " + grid_name + " is not a float grid");
    std::size_t outside = 0;
    std::vector<float> out = activeOnLattice(*grid, spec.nodes(), outside);
    if (outside > 0) throw std::runtime_error(path + ": " + grid_name + " reaches beyond the box");
    return out;
  } catch (const openvdb::Exception& e) {
    throw std::runtime_error(path + ": cannot read the VDB file: " + e.what());
  }
}

}  // namespace glint
