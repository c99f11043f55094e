// libFuzzer target of the glTF loader (tests/fuzz/README.md): any bytes, read as a .glb or a
// .gltf from a stranger, must give a model or an InputError. Any other exception, a crash, a
// sanitizer report, a hang or a huge allocation is a bug in glint's loader (or in tinygltf,
// which the loader must then keep away from such input).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <span>

#include "fuzz_limits.h"
#include "pipeline/base/input_error.h"
#include "pipeline/input/gltf_loader.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // External buffer uris resolve in the seed corpus folder, so inputs can reach real files
  // there (and the loader's confinement refuses everything else).
  static const std::filesystem::path folder = GLINT_FUZZ_GLTF_DIR;
  static const glint::GltfLimits limits = glint::fuzz::modelLimits();
  try {
    glint::parseGltf(std::span<const unsigned char>(data, size), "fuzz.gltf", folder, limits);
  } catch (const glint::InputError&) {
    // The contract: bad input is refused with an InputError, nothing else.
  }
  return 0;
}
