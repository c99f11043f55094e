// libFuzzer target of the scene file parser (tests/fuzz/README.md): any text must give a
// validated scene or an InputError. Any other exception, a crash, a sanitizer report, a hang or
// a huge allocation is a bug. Mesh objects name their `file` relative to the glTF seed corpus,
// so inputs reach real .glb and .gltf models (e.g. "file": "capsule.glb") and the glTF loader
// behind the scene parser.
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string_view>

#include "fuzz_limits.h"
#include "pipeline/base/input_error.h"
#include "pipeline/input/scene.h"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const std::optional<std::filesystem::path> folder{GLINT_FUZZ_GLTF_DIR};
  static const glint::GltfLimits limits = glint::fuzz::modelLimits();
  try {
    glint::parseScene(std::string_view(reinterpret_cast<const char*>(data), size), "fuzz.json",
                      folder, limits);
  } catch (const glint::InputError&) {
    // The contract: bad input is refused with an InputError, nothing else.
  }
  return 0;
}
