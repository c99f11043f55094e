#include "facets/target.h"

namespace glint {
namespace {
template <class T>
std::uint32_t append(std::vector<T>& v, const T& x) {
  v.push_back(x);
  return static_cast<std::uint32_t>(v.size() - 1);
}
}  // namespace

std::uint32_t Target::addMaterial(const Material& m) { return append(materials, m); }
std::uint32_t Target::addObject(const TargetObject& o) { return append(objects, o); }
std::uint32_t Target::addQuadric(const Quadric& q) { return append(quadrics, q); }
std::uint32_t Target::addPNTriangle(const PNTriangle& t) { return append(pn_triangles, t); }

void Target::addFacet(std::uint32_t object_index, const std::array<Vec3, 3>& corners,
                      SurfaceModel surface, std::uint32_t surface_index, std::uint8_t rim) {
  corners_m.push_back(corners);
  object.push_back(object_index);
  model.push_back(surface);
  model_index.push_back(surface_index);
  rim_edges.push_back(rim);
}

}  // namespace glint
