#include "pipeline/input/gltf_loader.h"

#include <tiny_gltf.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <fstream>
#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/quaternion.hpp>
#include <glm/mat3x3.hpp>
#include <glm/mat4x4.hpp>
#include <limits>
#include <optional>
#include <vector>

#include "pipeline/base/input_error.h"

namespace glint {
namespace {

namespace fs = std::filesystem;

// --- Before tinygltf sees the bytes -------------------------------------------------------

// tinygltf 2.7.0 parses with nlohmann::json and frees the tree recursively, so a few hundred
// thousand nested brackets overflow the stack. glTF itself nests about 8 deep.
void checkJsonDepth(std::span<const unsigned char> json, int max_depth, const std::string& name) {
  int depth = 0;
  bool in_string = false;
  bool escaped = false;
  for (unsigned char c : json) {
    if (in_string) {
      if (escaped) {
        escaped = false;
      } else if (c == '\\') {
        escaped = true;
      } else if (c == '"') {
        in_string = false;
      }
    } else if (c == '"') {
      in_string = true;
    } else if (c == '[' || c == '{') {
      if (++depth > max_depth) {
        throw InputError(name + ": JSON nested deeper than " + std::to_string(max_depth) +
                         " levels; not a glTF model");
      }
    } else if (c == ']' || c == '}') {
      --depth;
    }
  }
}

std::uint32_t readU32(std::span<const unsigned char> bytes, std::size_t at) {
  std::uint32_t v = 0;
  std::memcpy(&v, bytes.data() + at, sizeof v);
  return v;  // little-endian, as glint's platforms are
}

bool isBinary(std::span<const unsigned char> bytes) {
  return bytes.size() >= 4 && std::memcmp(bytes.data(), "glTF", 4) == 0;
}

// The JSON chunk of a .glb, after checking the header and chunk bounds.
std::span<const unsigned char> glbJson(std::span<const unsigned char> bytes,
                                       const std::string& name) {
  if (bytes.size() < 20) throw InputError(name + ": truncated .glb header");
  if (readU32(bytes, 4) != 2) throw InputError(name + ": not glTF version 2");
  if (readU32(bytes, 8) > bytes.size()) throw InputError(name + ": .glb longer than the file");
  const std::uint32_t json_bytes = readU32(bytes, 12);
  if (readU32(bytes, 16) != 0x4E4F534Au) throw InputError(name + ": .glb without a JSON chunk");
  if (json_bytes > bytes.size() - 20) throw InputError(name + ": .glb JSON chunk out of bounds");
  return bytes.subspan(20, json_bytes);
}

// --- What tinygltf may do with the file system ---------------------------------------------

// The user data of the file-system callbacks: the one folder they may read from.
struct Confinement {
  fs::path folder;  // canonical
  std::uintmax_t max_bytes = 0;
  std::string refusal;  // why the first file was refused, for the message
};

// The canonical path of @p path if it is a regular file inside the folder and not too large.
std::optional<fs::path> confined(const std::string& path, Confinement& c) {
  // tinygltf looks for a uri in the model's folder and then in "."; the first answer is the
  // one that explains the failure.
  auto refuse = [&](const std::string& why) -> std::optional<fs::path> {
    if (c.refusal.empty()) c.refusal = "\"" + path + "\" " + why;
    return std::nullopt;
  };
  std::error_code ec;
  const fs::path real = fs::canonical(fs::path(path), ec);
  if (ec) return refuse("does not exist");
  const auto [end, rest] =
      std::mismatch(c.folder.begin(), c.folder.end(), real.begin(), real.end());
  if (end != c.folder.end()) return refuse("lies outside the model's folder " + c.folder.string());
  if (!fs::is_regular_file(real, ec)) return refuse("is not a regular file");
  const std::uintmax_t size = fs::file_size(real, ec);
  if (ec || size > c.max_bytes)
    return refuse("is larger than " + std::to_string(c.max_bytes) + " bytes");
  return real;
}

bool fileExists(const std::string& path, void* user) {
  return confined(path, *static_cast<Confinement*>(user)).has_value();
}

// The default expands the path with wordexp(), a shell's word expansion of text from the file.
std::string expandFilePath(const std::string& path, void*) { return path; }

bool readWholeFile(std::vector<unsigned char>* out, std::string* err, const std::string& path,
                   void* user) {
  Confinement& c = *static_cast<Confinement*>(user);
  const auto real = confined(path, c);
  if (!real) {
    if (err) *err += c.refusal + "\n";
    return false;
  }
  std::ifstream in(*real, std::ios::binary);
  out->assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) {
    if (err) *err += "cannot read \"" + path + "\"\n";
    return false;
  }
  return true;
}

bool refuseWrite(std::string* err, const std::string&, const std::vector<unsigned char>&, void*) {
  if (err) *err += "glint never writes through the glTF loader\n";
  return false;
}

// Textures are not reflectance: nothing is decoded, so no image parser sees the bytes.
bool skipImage(tinygltf::Image*, const int, std::string*, std::string*, int, int,
               const unsigned char*, int, void*) {
  return true;
}

// --- After tinygltf: every index and number checked before use ------------------------------

class Reader {
 public:
  Reader(const tinygltf::Model& model, const std::string& name, const GltfLimits& limits)
      : model_(model), name_(name), limits_(limits) {}

  GltfModel read() {
    std::vector<int> roots;
    if (!model_.scenes.empty()) {
      const int scene = model_.defaultScene >= 0 ? model_.defaultScene : 0;
      if (scene >= static_cast<int>(model_.scenes.size()))
        fail("scene " + std::to_string(scene) + " does not exist");
      roots = model_.scenes[scene].nodes;
    } else {
      // No scene: every node that is nobody's child.
      std::vector<bool> child(model_.nodes.size(), false);
      for (const auto& n : model_.nodes)
        for (int c : n.children)
          if (c >= 0 && c < static_cast<int>(child.size())) child[c] = true;
      for (std::size_t i = 0; i < child.size(); ++i)
        if (!child[i]) roots.push_back(static_cast<int>(i));
    }
    on_path_.assign(model_.nodes.size(), false);
    // Counted first, from the accessors' counts, so that a caller may refuse the model before
    // anything is decoded; the node tree's limits hold by then.
    if (limits_.before_decoding) {
      counting_ = true;
      for (int root : roots) visit(root, glm::dmat4(1.0), 0);
      counting_ = false;
      instances_ = 0;
      limits_.before_decoding(counts_);
    }
    for (int root : roots) visit(root, glm::dmat4(1.0), 0);
    if (out_.mesh.triangles.empty()) fail("no triangles in the model's scene");
    return std::move(out_);
  }

 private:
  [[noreturn]] void fail(const std::string& what) const { throw InputError(name_ + ": " + what); }
  // Named only on failure: a node is visited once per instance, up to a million times.
  [[noreturn]] void failNode(int index, const std::string& what) const {
    fail("/nodes/" + std::to_string(index) + what);
  }

  static bool finite(const glm::dmat4& m) {
    for (int c = 0; c < 4; ++c)
      for (int r = 0; r < 4; ++r)
        if (!std::isfinite(m[c][r])) return false;
    return true;
  }

  glm::dmat4 localTransform(const tinygltf::Node& node, int index) const {
    if (!node.matrix.empty()) {
      if (node.matrix.size() != 16) failNode(index, ": matrix must have 16 numbers");
      glm::dmat4 m;
      for (int i = 0; i < 16; ++i) m[i / 4][i % 4] = node.matrix[i];  // column-major, as glTF
      if (!finite(m)) failNode(index, ": matrix is not finite");
      return m;
    }
    glm::dmat4 t(1.0), r(1.0), s(1.0);
    if (!node.translation.empty()) {
      if (node.translation.size() != 3) failNode(index, ": translation must have 3 numbers");
      t = glm::translate(glm::dmat4(1.0),
                         Vec3(node.translation[0], node.translation[1], node.translation[2]));
    }
    if (!node.rotation.empty()) {
      if (node.rotation.size() != 4) failNode(index, ": rotation must have 4 numbers");
      const glm::dquat q(node.rotation[3], node.rotation[0], node.rotation[1], node.rotation[2]);
      const double len = glm::length(q);
      if (!(len > 0.5 && len < 2.0)) failNode(index, ": rotation is not a unit quaternion");
      r = glm::mat4_cast(q / len);
    }
    if (!node.scale.empty()) {
      if (node.scale.size() != 3) failNode(index, ": scale must have 3 numbers");
      s = glm::scale(glm::dmat4(1.0), Vec3(node.scale[0], node.scale[1], node.scale[2]));
    }
    const glm::dmat4 m = t * r * s;
    if (!finite(m)) failNode(index, ": translation, rotation or scale is not finite");
    return m;
  }

  void visit(int index, const glm::dmat4& parent, int depth) {
    if (index < 0 || index >= static_cast<int>(model_.nodes.size()))
      failNode(index, " does not exist");
    if (on_path_[index]) failNode(index, " is its own ancestor (a cycle in the node tree)");
    if (depth > limits_.max_json_depth)
      failNode(index, ": node tree deeper than " + std::to_string(limits_.max_json_depth));
    // A node may be the child of many: a graph that shares nodes level by level names 2^depth
    // instances with a handful of nodes, so the instances are counted, not the nodes.
    if (++instances_ > limits_.max_node_instances)
      fail("more than " + std::to_string(limits_.max_node_instances) +
           " node instances (nodes shared as children over and over)");
    const tinygltf::Node& node = model_.nodes[index];
    const glm::dmat4 m = parent * localTransform(node, index);
    if (node.mesh >= 0) {
      if (counting_) {
        countMesh(node.mesh);
      } else {
        addMesh(node.mesh, m, index);
      }
    }
    on_path_[index] = true;
    for (int child : node.children) visit(child, m, depth + 1);
    on_path_[index] = false;
  }

  struct View {
    const unsigned char* data = nullptr;
    std::size_t stride = 0;
    std::size_t count = 0;
    int component_type = 0;
  };

  // Accessor @p index checked against its buffer view and buffer: every element it names
  // lies inside the buffer.
  View accessor(int index, int type, std::initializer_list<int> component_types,
                const std::string& where) const {
    const std::string at = where + " (/accessors/" + std::to_string(index) + ")";
    if (index < 0 || index >= static_cast<int>(model_.accessors.size()))
      fail(at + " does not exist");
    const tinygltf::Accessor& a = model_.accessors[index];
    if (a.sparse.isSparse) fail(at + ": sparse accessors are not supported");
    if (a.type != type) fail(at + ": wrong type for this attribute");
    if (std::find(component_types.begin(), component_types.end(), a.componentType) ==
        component_types.end())
      fail(at + ": wrong component type for this attribute");
    if (a.count == 0) fail(at + ": count is 0");
    if (a.bufferView < 0 || a.bufferView >= static_cast<int>(model_.bufferViews.size()))
      fail(at + ": no valid bufferView");
    const tinygltf::BufferView& v = model_.bufferViews[a.bufferView];
    if (v.buffer < 0 || v.buffer >= static_cast<int>(model_.buffers.size()))
      fail(at + ": its bufferView names no valid buffer");
    const std::vector<unsigned char>& data = model_.buffers[v.buffer].data;
    if (v.byteOffset > data.size() || v.byteLength > data.size() - v.byteOffset)
      fail(at + ": its bufferView runs past the end of its buffer");
    const std::size_t component =
        static_cast<std::size_t>(tinygltf::GetComponentSizeInBytes(a.componentType));
    const std::size_t element =
        component * static_cast<std::size_t>(tinygltf::GetNumComponentsInType(a.type));
    const std::size_t stride = v.byteStride ? v.byteStride : element;
    if (stride < element || stride % component != 0) fail(at + ": bad byteStride");
    // The last element must end inside the view: offset + (count − 1)·stride + element.
    const std::size_t room = v.byteLength;
    if (a.byteOffset > room || element > room - a.byteOffset ||
        a.count - 1 > (room - a.byteOffset - element) / stride)
      fail(at + ": " + std::to_string(a.count) + " elements do not fit in its bufferView");
    return {data.data() + v.byteOffset + a.byteOffset, stride, a.count, a.componentType};
  }

  std::vector<Vec3> vectors(const View& view, const std::string& what) const {
    std::vector<Vec3> out(view.count);
    for (std::size_t i = 0; i < view.count; ++i) {
      float xyz[3];
      std::memcpy(xyz, view.data + i * view.stride, sizeof xyz);
      for (int c = 0; c < 3; ++c) {
        if (!std::isfinite(xyz[c]))
          fail(what + ": element " + std::to_string(i) + " is not finite");
        out[i][c] = static_cast<double>(xyz[c]);
      }
    }
    return out;
  }

  std::vector<std::uint32_t> indices(const View& view) const {
    std::vector<std::uint32_t> out(view.count);
    for (std::size_t i = 0; i < view.count; ++i) {
      const unsigned char* p = view.data + i * view.stride;
      switch (view.component_type) {
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE:
          out[i] = *p;
          break;
        case TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT: {
          std::uint16_t v;
          std::memcpy(&v, p, sizeof v);
          out[i] = v;
          break;
        }
        default:
          std::memcpy(&out[i], p, sizeof out[i]);
          break;
      }
    }
    return out;
  }

  // What addMesh() will make of an instance of mesh @p mesh_index, from its accessors' counts
  // (checked as addMesh() checks them, not decoded), refused at the same limits.
  void countMesh(int mesh_index) {
    if (mesh_index >= static_cast<int>(model_.meshes.size())) return;  // addMesh() says so
    const auto& primitives = model_.meshes[mesh_index].primitives;
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      const tinygltf::Primitive& prim = primitives[k];
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN)
        continue;
      const std::string at =
          "/meshes/" + std::to_string(mesh_index) + "/primitives/" + std::to_string(k);
      const auto pos = prim.attributes.find("POSITION");
      if (pos == prim.attributes.end()) fail(at + ": no POSITION");
      const std::size_t vertices = accessor(pos->second, TINYGLTF_TYPE_VEC3,
                                            {TINYGLTF_COMPONENT_TYPE_FLOAT}, at + " POSITION")
                                       .count;
      const std::size_t corners = prim.indices < 0
                                      ? vertices
                                      : accessor(prim.indices, TINYGLTF_TYPE_SCALAR,
                                                 {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE,
                                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                                                  TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                                                 at + " indices")
                                            .count;
      const std::size_t triangles = mode == TINYGLTF_MODE_TRIANGLES ? corners / 3
                                    : corners >= 3                  ? corners - 2
                                                                    : 0;
      if (vertices > 3 * limits_.max_triangles - counts_.vertices)
        fail("more than " + std::to_string(3 * limits_.max_triangles) + " vertices");
      if (triangles > limits_.max_triangles - counts_.triangles)
        fail("more than " + std::to_string(limits_.max_triangles) + " triangles");
      counts_.vertices += vertices;
      counts_.triangles += triangles;
    }
  }

  void addMesh(int mesh_index, const glm::dmat4& m, int node) {
    if (mesh_index >= static_cast<int>(model_.meshes.size()))
      failNode(node, " mesh " + std::to_string(mesh_index) + " does not exist");
    const glm::dmat3 linear(m);
    const double det = glm::determinant(linear);
    if (!(std::abs(det) > 0.0) || !std::isfinite(det)) failNode(node, ": singular transform");
    const glm::dmat3 normal_matrix = glm::transpose(glm::inverse(linear));
    const bool mirrored = det < 0.0;
    out_.mirrored_instances += mirrored;
    const auto& primitives = model_.meshes[mesh_index].primitives;
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      const tinygltf::Primitive& prim = primitives[k];
      const std::string at =
          "/meshes/" + std::to_string(mesh_index) + "/primitives/" + std::to_string(k);
      const int mode = prim.mode < 0 ? TINYGLTF_MODE_TRIANGLES : prim.mode;
      if (mode != TINYGLTF_MODE_TRIANGLES && mode != TINYGLTF_MODE_TRIANGLE_STRIP &&
          mode != TINYGLTF_MODE_TRIANGLE_FAN) {
        ++out_.primitives_skipped;
        continue;
      }
      const auto pos = prim.attributes.find("POSITION");
      if (pos == prim.attributes.end()) fail(at + ": no POSITION");
      const View positions = accessor(pos->second, TINYGLTF_TYPE_VEC3,
                                      {TINYGLTF_COMPONENT_TYPE_FLOAT}, at + " POSITION");
      // Every instance copies its primitive's vertices, used or not: counted before reading.
      if (positions.count > 3 * limits_.max_triangles - out_.mesh.positions_m.size())
        fail("more than " + std::to_string(3 * limits_.max_triangles) + " vertices");
      const std::vector<Vec3> p = vectors(positions, at + " POSITION");
      std::vector<Vec3> n(p.size(), Vec3(0.0));
      const auto nrm = prim.attributes.find("NORMAL");
      if (nrm != prim.attributes.end()) {
        n = vectors(accessor(nrm->second, TINYGLTF_TYPE_VEC3, {TINYGLTF_COMPONENT_TYPE_FLOAT},
                             at + " NORMAL"),
                    at + " NORMAL");
        if (n.size() != p.size()) fail(at + ": NORMAL and POSITION counts differ");
      } else {
        out_.vertices_without_normal += p.size();
      }
      std::vector<std::uint32_t> idx;
      if (prim.indices >= 0) {
        idx = indices(
            accessor(prim.indices, TINYGLTF_TYPE_SCALAR,
                     {TINYGLTF_COMPONENT_TYPE_UNSIGNED_BYTE, TINYGLTF_COMPONENT_TYPE_UNSIGNED_SHORT,
                      TINYGLTF_COMPONENT_TYPE_UNSIGNED_INT},
                     at + " indices"));
        for (std::size_t i = 0; i < idx.size(); ++i)
          if (idx[i] >= p.size())
            fail(at + ": index " + std::to_string(i) + " is " + std::to_string(idx[i]) +
                 ", not below the vertex count " + std::to_string(p.size()));
      } else {
        idx.resize(p.size());
        for (std::size_t i = 0; i < idx.size(); ++i) idx[i] = static_cast<std::uint32_t>(i);
      }
      if (mode == TINYGLTF_MODE_TRIANGLES && idx.size() % 3 != 0)
        fail(at + ": " + std::to_string(idx.size()) + " indices do not make whole triangles");
      if (idx.size() < 3) fail(at + ": fewer than 3 vertices");
      const std::size_t triangles =
          mode == TINYGLTF_MODE_TRIANGLES ? idx.size() / 3 : idx.size() - 2;
      if (triangles > limits_.max_triangles - out_.mesh.triangles.size())
        fail("more than " + std::to_string(limits_.max_triangles) + " triangles");

      const auto base = static_cast<std::uint32_t>(out_.mesh.positions_m.size());
      for (std::size_t i = 0; i < p.size(); ++i) {
        const Vec3 x = Vec3(m * glm::dvec4(p[i], 1.0));
        out_.mesh.positions_m.push_back(x);
        out_.mesh.normals.push_back(tryNormalize(normal_matrix * n[i]).value_or(Vec3(0.0)));
      }
      for (std::size_t t = 0; t < triangles; ++t) {
        std::array<std::uint32_t, 3> tri;
        if (mode == TINYGLTF_MODE_TRIANGLES) {
          tri = {idx[3 * t], idx[3 * t + 1], idx[3 * t + 2]};
        } else if (mode == TINYGLTF_MODE_TRIANGLE_STRIP) {
          tri = t % 2 == 0 ? std::array{idx[t], idx[t + 1], idx[t + 2]}
                           : std::array{idx[t + 1], idx[t], idx[t + 2]};
        } else {
          tri = {idx[0], idx[t + 1], idx[t + 2]};
        }
        if (mirrored) std::swap(tri[1], tri[2]);
        out_.mesh.triangles.push_back({base + tri[0], base + tri[1], base + tri[2]});
      }
      ++out_.primitives;
    }
  }

  const tinygltf::Model& model_;
  const std::string& name_;
  const GltfLimits& limits_;
  std::vector<bool> on_path_;
  std::size_t instances_ = 0;
  bool counting_ = false;  // the first pass: countMesh(), nothing decoded
  GltfCounts counts_;
  GltfModel out_;
};

}  // namespace

GltfModel parseGltf(std::span<const unsigned char> bytes, const std::string& name,
                    const fs::path& folder, const GltfLimits& limits) {
  if (bytes.size() > limits.max_file_bytes || bytes.size() > std::numeric_limits<unsigned>::max())
    throw InputError(name + ": larger than " + std::to_string(limits.max_file_bytes) + " bytes");
  const bool binary = isBinary(bytes);
  // Neither a .glb nor JSON text: refused without quoting it, since a scene can name any file
  // (a system file by a ../ path) and its bytes have no place in a message.
  if (!binary) {
    const auto first = std::find_if(bytes.begin(), bytes.end(), [](unsigned char c) {
      return c != ' ' && c != '\t' && c != '\n' && c != '\r';
    });
    if (first == bytes.end() || *first != '{')
      throw InputError(name + ": not a glTF model (neither a binary .glb nor a JSON object)");
  }
  checkJsonDepth(binary ? glbJson(bytes, name) : bytes, limits.max_json_depth, name);

  std::error_code ec;
  Confinement confinement{
      fs::canonical(folder.empty() ? fs::path(".") : folder, ec), limits.max_file_bytes, {}};
  if (ec) throw InputError(name + ": cannot resolve its folder " + folder.string());
  tinygltf::TinyGLTF loader;
  loader.SetFsCallbacks({&fileExists, &expandFilePath, &readWholeFile, &refuseWrite, &confinement});
  loader.SetImageLoader(&skipImage, nullptr);
  tinygltf::Model model;
  std::string err, warn;
  bool ok = false;
  try {
    const auto length = static_cast<unsigned>(bytes.size());
    ok = binary ? loader.LoadBinaryFromMemory(&model, &err, &warn, bytes.data(), length,
                                              confinement.folder.string())
                : loader.LoadASCIIFromString(&model, &err, &warn,
                                             reinterpret_cast<const char*>(bytes.data()), length,
                                             confinement.folder.string());
  } catch (const std::exception& e) {
    throw InputError(name + ": not a readable glTF model (" + e.what() + ")");
  }
  if (!ok) {
    // The JSON parser quotes what it last read: the position is enough, the bytes stay out.
    if (const auto quote = err.find("; last read:"); quote != std::string::npos) err.resize(quote);
    while (!err.empty() && (err.back() == '\n' || err.back() == ' ')) err.pop_back();
    err = printable(err, 240);
    if (!confinement.refusal.empty()) throw InputError(name + ": refused: " + confinement.refusal);
    throw InputError(name +
                     ": not a readable glTF model: " + (err.empty() ? "unknown error" : err));
  }
  return Reader(model, name, limits).read();
}

GltfModel loadGltf(const fs::path& file, const GltfLimits& limits) {
  const std::string name = file.string();
  std::error_code ec;
  if (!fs::is_regular_file(file, ec)) throw InputError(name + ": not a file (the mesh's `file`)");
  const std::uintmax_t size = fs::file_size(file, ec);
  if (ec || size > limits.max_file_bytes)
    throw InputError(name + ": larger than " + std::to_string(limits.max_file_bytes) + " bytes");
  std::ifstream in(file, std::ios::binary);
  std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
  if (!in.eof() && in.fail()) throw InputError(name + ": cannot read the model");
  return parseGltf(bytes, name, file.parent_path(), limits);
}

}  // namespace glint
