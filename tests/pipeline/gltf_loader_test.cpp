// The glTF loader: node transforms, and the hostile files it must refuse with a clear message
// (docs/meshes.md, "A file from a stranger": traversal, a folder as uri, deep nesting, bad
// accessors, NaN vertices).
#include "pipeline/input/gltf_loader.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "pipeline/base/input_error.h"
#include "pipeline/input/scene.h"
#include "support/refusal.h"

namespace glint {
namespace {

namespace fs = std::filesystem;
using json = nlohmann::json;

// A scratch folder per test, removed afterwards.
class GltfLoader : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() / (std::string("glint_gltf_") + info->name());
    fs::remove_all(dir_);
    fs::create_directories(dir_ / "model");
  }
  void TearDown() override { fs::remove_all(dir_); }

  // One triangle (or what `positions` and `indices` say) in model/<name>.gltf with its
  // buffer in model/<name>.bin; `edit` may change the JSON before it is written.
  fs::path write(
      const std::string& name, std::vector<float> positions, std::vector<std::uint16_t> indices,
      const std::function<void(json&)>& edit = [](json&) {}) const {
    std::vector<unsigned char> bin(positions.size() * 4 + indices.size() * 2);
    std::memcpy(bin.data(), positions.data(), positions.size() * 4);
    std::memcpy(bin.data() + positions.size() * 4, indices.data(), indices.size() * 2);
    std::ofstream(dir_ / "model" / (name + ".bin"), std::ios::binary)
        .write(reinterpret_cast<const char*>(bin.data()), static_cast<std::streamsize>(bin.size()));
    json j = {{"asset", {{"version", "2.0"}}},
              {"scene", 0},
              {"scenes", {{{"nodes", {0}}}}},
              {"nodes", {{{"mesh", 0}}}},
              {"meshes", {{{"primitives", {{{"attributes", {{"POSITION", 0}}}, {"indices", 1}}}}}}},
              {"buffers", {{{"uri", name + ".bin"}, {"byteLength", bin.size()}}}},
              {"bufferViews",
               {{{"buffer", 0}, {"byteOffset", 0}, {"byteLength", positions.size() * 4}},
                {{"buffer", 0},
                 {"byteOffset", positions.size() * 4},
                 {"byteLength", indices.size() * 2}}}},
              {"accessors",
               {{{"bufferView", 0},
                 {"componentType", 5126},
                 {"count", positions.size() / 3},
                 {"type", "VEC3"}},
                {{"bufferView", 1},
                 {"componentType", 5123},
                 {"count", indices.size()},
                 {"type", "SCALAR"}}}}};
    edit(j);
    const fs::path file = dir_ / "model" / (name + ".gltf");
    std::ofstream(file) << j.dump();
    return file;
  }

  fs::path dir_;
};

const std::vector<float> kTriangle = {0, 0, 0, 1, 0, 0, 0, 1, 0};

// A scene of one object, lit from 10 m above by a 1 W flat-top beam; material "m".
json sceneOf(const json& object) {
  return {{"laser",
           {{"position", {0, 0, 10}},
            {"direction", {0, 0, -1}},
            {"power_w", 1.0},
            {"wavelength_nm", 532},
            {"beam", {{"profile", "flat_top"}, {"radius_m", 1.0}}}}},
          {"materials", {{"m", {{"specular_reflectance", 0.5}, {"sigma", 0.1}}}}},
          {"objects", json::array({object})}};
}

// The message loadGltf refuses `file` with.
std::string refusal(const fs::path& file) {
  return test::refusalOf([&] { loadGltf(file); });
}

TEST_F(GltfLoader, AppliesNodeTransformsAndFlipsMirroredWinding) {
  const fs::path file = write("t", kTriangle, {0, 1, 2}, [](json& j) {
    j["nodes"] = {
        {{"children", {1}}, {"translation", {10, 0, 0}}},
        {{"mesh", 0}, {"rotation", {0, 0, std::sqrt(0.5), std::sqrt(0.5)}}},  // 90° about z
        {{"mesh", 0}, {"scale", {-1, 1, 1}}}};
    j["scenes"] = {{{"nodes", {0, 2}}}};
  });
  const GltfModel m = loadGltf(file);
  ASSERT_EQ(m.mesh.triangles.size(), 2u);
  EXPECT_EQ(m.mirrored_instances, 1u);
  const auto& p = m.mesh.positions_m;
  // (1, 0, 0) turned 90° about z is (0, 1, 0), then moved 10 m along x.
  EXPECT_NEAR(p[1].x, 10.0, 1e-12);
  EXPECT_NEAR(p[1].y, 1.0, 1e-12);
  // Both instances still face +z: the mirror's winding was flipped back.
  for (const auto& t : m.mesh.triangles) {
    const Vec3 n = glm::cross(p[t[1]] - p[t[0]], p[t[2]] - p[t[0]]);
    EXPECT_GT(n.z, 0.0) << "triangle " << t[0] << " faces " << n.z;
  }
  EXPECT_EQ(m.vertices_without_normal, 6u);
}

TEST_F(GltfLoader, RefusesAUriOutsideTheModelsFolder) {
  std::ofstream(dir_ / "secret.bin") << std::string(64, 'x');
  const fs::path file =
      write("t", kTriangle, {0, 1, 2}, [](json& j) { j["buffers"][0]["uri"] = "../secret.bin"; });
  EXPECT_NE(refusal(file).find("outside the model's folder"), std::string::npos) << refusal(file);
  const fs::path absolute =
      write("a", kTriangle, {0, 1, 2}, [](json& j) { j["buffers"][0]["uri"] = "/etc/passwd"; });
  EXPECT_NE(refusal(absolute).find("refused"), std::string::npos) << refusal(absolute);
}

TEST_F(GltfLoader, RefusesAUriNamingAFolder) {
  fs::create_directories(dir_ / "model" / "sub");
  const fs::path file =
      write("t", kTriangle, {0, 1, 2}, [](json& j) { j["buffers"][0]["uri"] = "sub"; });
  EXPECT_NE(refusal(file).find("not a regular file"), std::string::npos) << refusal(file);
}

TEST_F(GltfLoader, RefusesDeepNestingBeforeParsing) {
  const fs::path file = dir_ / "model" / "deep.gltf";
  std::ofstream(file) << R"({"asset": {"version": "2.0"}, "extras": )" << std::string(200000, '[')
                      << std::string(200000, ']') << "}";
  EXPECT_NE(refusal(file).find("nested deeper than 64"), std::string::npos) << refusal(file);
}

TEST_F(GltfLoader, RefusesAnAccessorLongerThanItsBufferView) {
  const fs::path file =
      write("t", kTriangle, {0, 1, 2}, [](json& j) { j["accessors"][0]["count"] = 4; });
  EXPECT_NE(refusal(file).find("do not fit in its bufferView"), std::string::npos) << refusal(file);
  const fs::path view =
      write("v", kTriangle, {0, 1, 2}, [](json& j) { j["bufferViews"][0]["byteLength"] = 1000; });
  EXPECT_NE(refusal(view).find("runs past the end of its buffer"), std::string::npos)
      << refusal(view);
  const fs::path missing =
      write("m", kTriangle, {0, 1, 2}, [](json& j) { j["accessors"][0]["bufferView"] = 7; });
  EXPECT_NE(refusal(missing).find("no valid bufferView"), std::string::npos) << refusal(missing);
}

TEST_F(GltfLoader, RefusesACountOfZero) {
  const fs::path file =
      write("t", kTriangle, {0, 1, 2}, [](json& j) { j["accessors"][1]["count"] = 0; });
  EXPECT_NE(refusal(file).find("count is 0"), std::string::npos) << refusal(file);
}

TEST_F(GltfLoader, RefusesIndicesBeyondTheVertices) {
  const fs::path file = write("t", kTriangle, {0, 1, 7});
  EXPECT_NE(refusal(file).find("is 7, not below the vertex count 3"), std::string::npos)
      << refusal(file);
}

TEST_F(GltfLoader, RefusesNonFiniteVertices) {
  std::vector<float> p = kTriangle;
  p[4] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_NE(refusal(write("nan", p, {0, 1, 2})).find("POSITION: element 1 is not finite"),
            std::string::npos)
      << refusal(write("nan", p, {0, 1, 2}));
  p[4] = std::numeric_limits<float>::infinity();
  EXPECT_NE(refusal(write("inf", p, {0, 1, 2})).find("not finite"), std::string::npos);
}

TEST_F(GltfLoader, RefusesACycleInTheNodeTree) {
  const fs::path file = write("t", kTriangle, {0, 1, 2}, [](json& j) {
    j["nodes"] = {{{"children", {1}}}, {{"children", {0}}, {"mesh", 0}}};
  });
  EXPECT_NE(refusal(file).find("its own ancestor"), std::string::npos) << refusal(file);
}

TEST_F(GltfLoader, RefusesANodeGraphThatInstancesItselfExponentially) {
  // 60 nodes, each the child of the one before twice over: 2^60 instances of the last.
  const fs::path file = write("t", kTriangle, {0, 1, 2}, [](json& j) {
    json nodes = json::array();
    for (int i = 0; i < 60; ++i) nodes.push_back({{"children", {i + 1, i + 1}}});
    nodes.push_back({{"mesh", 0}});
    j["nodes"] = nodes;
  });
  EXPECT_NE(refusal(file).find("node instances"), std::string::npos) << refusal(file);
}

TEST_F(GltfLoader, RefusesWhatIsNotGltf) {
  const fs::path file = dir_ / "model" / "junk.glb";
  std::ofstream(file) << "glTF\x02\0\0\0 not really";
  EXPECT_NE(refusal(file).find(".glb"), std::string::npos) << refusal(file);
  EXPECT_NE(refusal(dir_ / "model").find("not a file"), std::string::npos);
}

// A scene may name any file (a system file by a ../ path): its bytes never reach the message,
// neither from the check before parsing nor from the JSON parser's "last read".
TEST_F(GltfLoader, QuotesNoContentOfAFileThatIsNotGltf) {
  const fs::path passwd = dir_ / "model" / "passwd";
  std::ofstream(passwd) << "root:x:0:0:secret\n";
  EXPECT_EQ(refusal(passwd),
            passwd.string() + ": not a glTF model (neither a binary .glb nor a JSON object)");
  const fs::path broken = dir_ / "model" / "broken.gltf";
  std::ofstream(broken) << "{\"asset\": secret\x07}";
  const std::string message = refusal(broken);
  EXPECT_EQ(message.find("secret"), std::string::npos) << message;
  EXPECT_EQ(message.find('\x07'), std::string::npos) << message;
  EXPECT_NE(message.find("not a readable glTF model"), std::string::npos) << message;
}

TEST_F(GltfLoader, AMeshWithNoUsableTriangleIsRefusedNamingTheFileAndTheCount) {
  // Two triangles, one with three corners on a line and one with a corner repeated: a model
  // that loads, and leaves no surface to reflect. The run must not read it as a safe target.
  write("flat", {0, 0, 0, 1, 0, 0, 2, 0, 0, 0, 1, 0}, {0, 1, 2, 0, 3, 3});
  const json scene = sceneOf({{"shape", "mesh"}, {"file", "model/flat.gltf"}, {"material", "m"}});
  const std::string message =
      test::refusalOf([&] { parseScene(scene.dump(), "scene.json", dir_); });
  EXPECT_NE(message.find("scene.json: /objects/0/file: "), std::string::npos) << message;
  EXPECT_NE(message.find("flat.gltf: none of its 2 triangles is usable"), std::string::npos)
      << message;
}

TEST(GltfExamples, TheExampleTargetsLoadWhole) {
  const fs::path dir = fs::path(GLINT_EXAMPLES_DIR) / "targets";
  const GltfModel capsule = loadGltf(dir / "capsule.glb");
  EXPECT_EQ(capsule.mesh.triangles.size(), 1216u);
  EXPECT_EQ(capsule.vertices_without_normal, 0u);
  const GltfModel missile = loadGltf(dir / "finned_missile.glb");
  EXPECT_EQ(missile.mesh.triangles.size(), 2016u + 4u * 12u) << "the body and four fin instances";
  const GltfModel car = loadGltf(dir / "car_body.glb");
  EXPECT_EQ(car.mesh.triangles.size(), 1458u);
  EXPECT_EQ(car.vertices_without_normal, car.mesh.positions_m.size()) << "the car has no normals";
}

TEST_F(GltfLoader, MeshObjectsAreReadRelativeToTheSceneAndPlaced) {
  write("t", kTriangle, {0, 1, 2});
  const json scene =
      sceneOf({{"shape", "mesh"},
               {"file", "model/t.gltf"},
               {"material", "m"},
               {"surface", "flat"},
               {"transform",
                {{"translation", {5, 0, 0}}, {"scale", 2.0}, {"yaw_pitch_roll_deg", {90, 0, 0}}}}});
  const Scene s = parseScene(scene.dump(), "scene.json", dir_);
  ASSERT_TRUE(s.objects[0].mesh());
  const MeshSpec& m = *s.objects[0].mesh();
  EXPECT_EQ(s.objects[0].centre_m(), Vec3(5, 0, 0));
  // (1, 0, 0) scaled by 2 and turned 90° about z: (0, 2, 0) from the centre.
  EXPECT_NEAR(m.mesh->positions_m[1].x, 0.0, 1e-12);
  EXPECT_NEAR(m.mesh->positions_m[1].y, 2.0, 1e-12);
  EXPECT_EQ(m.normals_computed, 3u);

  json bad = scene;
  bad["objects"][0]["file"] = "model/missing.gltf";
  try {
    parseScene(bad.dump(), "scene.json", dir_);
    ADD_FAILURE() << "a missing mesh file was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("scene.json: /objects/0/file:"), std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace glint
