#include "geo/terrain.h"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <vector>

#include "facets/detail/embree_triangles.h"
#include "geo/backend.h"

namespace glint {
namespace {

// What a post of the window costs the run (bytes), a floor under the measured figure
// (docs/terrain.md, "Memory").
constexpr std::uint64_t kBytesPerPost = 400;

}  // namespace

// The surface's triangles in an Embree scene of their own, about the surface's centre, for the
// vertical queries of surfaceZ(); the double-precision vertices answer them.
struct Terrain::Heights {
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  Vec3 origin_m{0.0};

  ~Heights() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
  }
};

Terrain::Terrain() = default;
Terrain::~Terrain() = default;

std::uint64_t Terrain::memoryBytes(std::size_t window_posts) {
  return static_cast<std::uint64_t>(window_posts) * kBytesPerPost;
}

std::shared_ptr<const Terrain> Terrain::read(
    const std::filesystem::path& dem_file, const SiteFrame& site, const HorizontalBox& region,
    std::size_t max_posts, const std::function<void(std::size_t)>& before_reading) {
  const std::string name = dem_file.string();
  const auto fail = [&](const std::string& what) { throw std::runtime_error(name + ": " + what); };
  const DemPosts posts = geoBackend().readDem(name, site.spec(), region, max_posts, before_reading);
  const std::size_t nc = posts.columns, nr = posts.rows;
  std::shared_ptr<Terrain> t(new Terrain());
  t->window_posts_ = nc * nr;
  t->crs_name_ = posts.crs_name;
  auto mesh = std::make_shared<ShadowMesh>();
  constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();
  std::vector<std::uint32_t> vertex(nc * nr, kNone);
  t->min_z_ = std::numeric_limits<double>::infinity();
  t->max_z_ = -t->min_z_;
  for (std::size_t k = 0; k < nc * nr; ++k) {
    if (posts.valid[k] == 0) continue;
    const Vec3& p = posts.local_m[k];
    vertex[k] = static_cast<std::uint32_t>(mesh->vertices_m.size());
    mesh->vertices_m.push_back(p);
    t->min_z_ = std::min(t->min_z_, p.z);
    t->max_z_ = std::max(t->max_z_, p.z);
  }
  const auto at = [&](std::size_t r, std::size_t c) { return vertex[r * nc + c]; };
  for (std::size_t r = 0; r + 1 < nr; ++r) {
    for (std::size_t c = 0; c + 1 < nc; ++c) {
      const std::uint32_t a = at(r, c), b = at(r, c + 1), e = at(r + 1, c + 1), f = at(r + 1, c);
      if (a == kNone || b == kNone || e == kNone || f == kNone) continue;
      mesh->triangles.push_back({a, b, e});
      mesh->triangles.push_back({a, e, f});
      for (const std::uint32_t n : {b, f}) {
        const Vec3 step = mesh->vertices_m[n] - mesh->vertices_m[a];
        t->post_spacing_m_ = std::max(t->post_spacing_m_, std::hypot(step.x, step.y));
      }
    }
  }
  if (mesh->triangles.empty()) fail("has no cell of four valid posts over the scene's region");
  t->posts_ = mesh->vertices_m.size();

  auto heights = std::make_unique<Heights>();
  Vec3 lo(std::numeric_limits<double>::infinity()), hi(-lo);
  for (const Vec3& p : mesh->vertices_m) lo = glm::min(lo, p), hi = glm::max(hi, p);
  heights->origin_m = 0.5 * (lo + hi);
  heights->device = rtcNewDevice(nullptr);
  if (!heights->device) throw std::runtime_error("Embree: cannot create a device");
  heights->scene = rtcNewScene(heights->device);
  rtcSetSceneFlags(heights->scene, RTC_SCENE_FLAG_ROBUST);
  detail::attachTriangles(heights->device, heights->scene, *mesh, heights->origin_m);
  rtcCommitScene(heights->scene);
  t->heights_ = std::move(heights);
  t->mesh_ = std::move(mesh);
  return t;
}

std::optional<double> Terrain::surfaceZ(double x_m, double y_m) const {
  const Heights& hs = *heights_;
  const double top = max_z_ + 1.0;
  RTCRayHit rh{};
  rh.ray.org_x = static_cast<float>(x_m - hs.origin_m.x);
  rh.ray.org_y = static_cast<float>(y_m - hs.origin_m.y);
  rh.ray.org_z = static_cast<float>(top - hs.origin_m.z);
  rh.ray.dir_z = -1.0f;
  rh.ray.tnear = 0.0f;
  rh.ray.tfar = static_cast<float>(max_z_ - min_z_ + 2.0);
  rh.ray.mask = 0xFFFFFFFFu;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  RTCIntersectContext context;
  rtcInitIntersectContext(&context);
  rtcIntersect1(hs.scene, &context, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  // The hit triangle's plane at (x, y), in double precision.
  const auto& tri = mesh_->triangles[rh.hit.primID];
  const Vec3& a = mesh_->vertices_m[tri[0]];
  const Vec3& b = mesh_->vertices_m[tri[1]];
  const Vec3& c = mesh_->vertices_m[tri[2]];
  const Vec3 n = glm::cross(b - a, c - a);
  if (std::abs(n.z) <= 1e-12 * glm::length(n)) return top - static_cast<double>(rh.ray.tfar);
  return a.z - (n.x * (x_m - a.x) + n.y * (y_m - a.y)) / n.z;
}

bool Terrain::segmentClear(const Vec3& from_m, const Vec3& to_m) const {
  const Vec3 d = to_m - from_m;
  const double length = glm::length(d);
  if (!(length > 2e-3)) return true;
  return detail::rayClear(heights_->scene, heights_->origin_m, from_m, d / length, 1e-3,
                          length - 1e-3);
}

}  // namespace glint
