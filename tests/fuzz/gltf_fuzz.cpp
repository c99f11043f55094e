// libFuzzer target of the glTF loader (tests/fuzz/README.md): any bytes, read as a .glb or a
// .gltf from a stranger, must give a model or an InputError. Any other exception, a crash, a
// sanitizer report, a hang or a huge allocation is a bug in glint's loader (or in tinygltf,
// which the loader must then keep away from such input).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>

#include "pipeline/gltf_loader.h"
#include "pipeline/input_error.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // External buffer uris resolve in the seed corpus folder, so inputs can reach real files
  // there (and the loader's confinement refuses everything else).
  static const std::filesystem::path folder = GLINT_FUZZ_GLTF_DIR;
  // Below the defaults: a model that legitimately asks for millions of triangles or a million
  // node instances takes gigabytes or seconds under the sanitizers, beyond the fuzzer's memory
  // and time limits (README.md), without being a bug; and a mutant of a seed that reaches a
  // limit should cost milliseconds, not the fuzzer's throughput.
  static const glint::GltfLimits limits = [] {
    glint::GltfLimits l;
    l.max_file_bytes = std::uintmax_t{1} << 20;
    l.max_triangles = 100'000;
    l.max_node_instances = 10'000;
    return l;
  }();
  try {
    glint::parseGltf(std::span<const unsigned char>(data, size), "fuzz.gltf", folder, limits);
  } catch (const glint::InputError&) {
    // The contract: bad input is refused with an InputError, nothing else.
  }
  return 0;
}
