// What a target and a far field take in memory, stage by stage: the resident set after each
// stage and its peak during it (Linux VmHWM, reset before each stage through
// /proc/self/clear_refs), per coarse facet, beside the estimate glint refuses by
// (targetMemory(), pipeline/setup/target_builder.h; farFieldMemoryFloorBytes(),
// observers/far_field.h).
//
//   glint_memory_bench SCENE.json [--segments N] [--points FILE.csv] [--far N] [--threads N]
//
// --segments overrides every analytic object's segments. Stages: the scene (meshes decoded),
// the target (buildTarget), the integrator (culling, surface maps, clusters, occluder); with
// --points the observers (evaluatePoints: the per-thread workspaces); with --far the far field
// at face_pixels N (two faces alone, then the whole map, then its lat-long map). The per-facet
// figures of the estimate were measured with it (README "Reliability", Memory).
#include <tbb/global_control.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cstdio>
#include <fstream>
#include <optional>
#include <string>

#include "observers/far_field.h"
#include "observers/point_set.h"
#include "pipeline/base/memory_budget.h"
#include "pipeline/input/points_file.h"
#include "pipeline/input/scene.h"
#include "pipeline/setup/target_builder.h"

using namespace glint;

namespace {

std::int64_t statusField(const char* key) {
  std::ifstream status("/proc/self/status");
  std::string line;
  const std::string prefix = std::string(key) + ":";
  while (std::getline(status, line)) {
    if (line.rfind(prefix, 0) == 0) return std::stoll(line.substr(prefix.size())) * 1024;
  }
  return 0;
}

double mb(std::int64_t bytes) { return static_cast<double>(bytes) / 1048576.0; }

void resetPeak() { std::ofstream("/proc/self/clear_refs") << "5"; }

struct Stage {
  std::int64_t before = 0;
  void start() {
    resetPeak();
    before = statusField("VmRSS");
  }
  void report(const char* name, std::size_t facets) {
    const std::int64_t rss = statusField("VmRSS"), peak = statusField("VmHWM");
    const double per = facets > 0 ? 1.0 / static_cast<double>(facets) : 0.0;
    std::printf("%-12s rss %+9.1f MB (%7.1f B/facet)  peak %+9.1f MB (%7.1f B/facet)\n", name,
                mb(rss - before), static_cast<double>(rss - before) * per, mb(peak - before),
                static_cast<double>(peak - before) * per);
  }
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app("glint memory bench");
  std::string scene_path, points_path;
  std::optional<int> segments;
  int threads = 0;
  int far_pixels = 0;
  app.add_option("scene", scene_path)->required();
  app.add_option("--segments", segments);
  app.add_option("--points", points_path);
  app.add_option("--threads", threads);
  app.add_option("--far", far_pixels, "the far field at this face_pixels");
  CLI11_PARSE(app, argc, argv);
  std::optional<tbb::global_control> limit;
  if (threads > 0) limit.emplace(tbb::global_control::max_allowed_parallelism, threads);

  const std::int64_t start = statusField("VmRSS");
  Stage stage;
  stage.start();
  Scene scene = loadScene(scene_path);
  if (segments) {
    for (ObjectSpec& o : scene.objects) o.segments = *segments;
  }
  const TargetMemory memory = targetMemory(scene, scene.accuracy);
  std::printf("estimate: %llu coarse facets, floor %.1f MB (+ %llu bytes a lit facet%s)\n",
              static_cast<unsigned long long>(memory.facets),
              static_cast<double>(memory.floor_bytes) / 1048576.0,
              static_cast<unsigned long long>(memory.lit_facet_bytes),
              memory.occlusion ? ", occluder" : "");
  stage.report("scene", 1);
  stage.start();
  Target target = buildTarget(scene);
  const std::size_t facets = target.facetCount();
  std::printf("%zu coarse facets\n", facets);
  stage.report("target", facets);
  stage.start();
  const FacetIntegrator integrator(std::move(target), scene.laser, scene.accuracy);
  stage.report("integrator", facets);
  std::printf("  lit %zu, occlusion %d\n", integrator.cullStats().lit,
              integrator.cullStats().occlusion ? 1 : 0);
  if (!points_path.empty()) {
    const std::vector<Vec3> points = loadPoints(points_path, std::uint64_t{1} << 30);
    stage.start();
    const auto results = evaluatePoints(integrator, points, PointScheme{});
    stage.report("observers", facets);
  }
  if (far_pixels > 0) {
    Scene far_scene = scene;
    far_scene.far_field.face_pixels = far_pixels;
    const FarFieldSpec spec = farFieldSpec(far_scene, integrator);
    const double directions = 6.0 * (far_pixels + 1.0) * (far_pixels + 1.0);
    for (int face = 0; face < 2; ++face) {
      stage.start();
      const FieldSpec f =
          cubeFaceSpec(face, litBall(integrator).centre_m, 1000.0 * spec.far_radius_m, spec);
      const FacetIntegrator at_face =
          integrator.withAccuracy(0.25 * f.tolerance, 0.25 * f.floor_w_m2);
      {
        const ObserverField field = computeField(at_face, f, ExcludedFn());
        stage.report("one face", facets);
        std::printf("  grids %.1f MB; per lattice point: divide by %.4g\n",
                    static_cast<double>(field.stats().grid_bytes) / 1048576.0,
                    (far_pixels + 1.0) * (far_pixels + 1.0) / static_cast<double>(facets));
        const std::vector<float> lattice = field.irradianceLattice();
        stage.report("+ lattice", facets);
      }
      stage.report("face freed", facets);
    }
    stage.start();
    const FarField far = computeFarField(integrator, spec);
    stage.report("far field", facets);
    std::printf("  %.4g directions; per direction: rss and peak as above / %.4g; grids %.1f MB\n",
                directions, directions / static_cast<double>(facets),
                static_cast<double>(far.stats().grid_bytes) / 1048576.0);
    stage.start();
    const int height = std::min(far_pixels, 2048);
    const LatLongMap map = latLongMap(far, height, scene.hazard.mpe_w_m2);
    stage.report("lat-long", facets);
    std::printf("  %d x %d pixels\n", map.width, map.height);
  }
  const std::int64_t end = statusField("VmRSS");
  std::printf("estimate with the lit facets: %.1f MB\n",
              (static_cast<double>(memory.floor_bytes) +
               static_cast<double>(integrator.cullStats().lit * memory.lit_facet_bytes)) /
                  1048576.0);
  std::printf("total rss growth %.1f MB (%.1f B/facet)\n",
              static_cast<double>(end - start) / 1048576.0,
              static_cast<double>(end - start) / static_cast<double>(facets));
  return 0;
}
