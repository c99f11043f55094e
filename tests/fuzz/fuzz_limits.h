#pragma once
// The model limits both fuzz targets load with, below glint's defaults: a model that
// legitimately asks for millions of triangles or a million node instances takes gigabytes or
// seconds under the sanitizers, beyond the fuzzer's per-input budget (README.md: -timeout=10,
// -rss_limit_mb=2048), without being a bug; and a mutant of a seed that reaches a limit should
// cost milliseconds, not the fuzzer's throughput. What such models reach beyond the loader (the
// crease normals at any valence) has its tests in tests/facets/mesh_test.cpp.
#include <cstdint>

#include "pipeline/input/gltf_loader.h"

namespace glint::fuzz {

inline GltfLimits modelLimits() {
  GltfLimits l;
  l.max_file_bytes = std::uintmax_t{1} << 20;
  l.max_triangles = 100'000;
  l.max_node_instances = 10'000;
  return l;
}

}  // namespace glint::fuzz
