#pragma once
/// @file
/// @brief Reads the triangles of a glTF 2.0 model (.glb or .gltf) through tinygltf, as a file
/// from a stranger: nothing outside the model's folder is read, nothing is decoded that glint
/// does not use, and every number is checked before it is used (docs/meshes.md, "A file from a
/// stranger").

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <span>
#include <string>

#include "facets/tessellate.h"

namespace glint {

/// @brief What a model's scene makes, counted from its accessors before any is decoded.
struct GltfCounts {
  std::size_t triangles = 0;  ///< after node instancing
  std::size_t vertices = 0;   ///< copied once per instance of their primitive
};

/// @brief What a model file may make glint read.
struct GltfLimits {
  std::uintmax_t max_file_bytes = std::uintmax_t{512} << 20;  ///< the model and each buffer
  int max_json_depth = 64;  ///< glTF needs about 8; a deep file is an attack
  /// After node instancing; vertices may be three times as many. A target of this size is
  /// already far beyond what a run over observers can afford.
  std::size_t max_triangles = 2'000'000;
  std::size_t max_node_instances = 1'000'000;  ///< nodes visited, each time it is a child
  /// Called with the model's counts once its JSON and buffers are read and the limits above
  /// hold, before any accessor is decoded: may throw (a memory budget refuses a model here).
  std::function<void(const GltfCounts&)> before_decoding;
};

/// @brief A model's triangles with the node transforms of its scene applied, in the model's
/// frame (glTF: metres, +Y up), and what the loader had to do about them.
struct GltfModel {
  TriangleMesh mesh;                        ///< normals zero where the file has none
  std::size_t vertices_without_normal = 0;  ///< vertices of primitives without NORMAL
  std::size_t primitives = 0;               ///< triangle primitives instanced
  std::size_t primitives_skipped = 0;       ///< points and lines: nothing to reflect
  std::size_t mirrored_instances = 0;       ///< nodes with a negative determinant (winding flipped)
};

/// @brief Loads @p file. Its external buffers must lie inside the file's folder.
/// @throw InputError naming the file and the problem.
GltfModel loadGltf(const std::filesystem::path& file, const GltfLimits& limits = {});

/// @brief Loads a model from @p bytes (binary or JSON), named @p name in messages; external
/// buffers are looked up inside @p folder only. What loadGltf() does after reading the file.
/// @throw InputError naming @p name and the problem.
GltfModel parseGltf(std::span<const unsigned char> bytes, const std::string& name,
                    const std::filesystem::path& folder, const GltfLimits& limits = {});

}  // namespace glint
