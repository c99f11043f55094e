#include <gtest/gtest.h>

#include <functional>
#include <tuple>

#include "facets/patch.h"
#include "facets/tessellate.h"

namespace glint {
namespace {

// Σ of the facet areas the kernel weights by, all facets split to `level`.
double areaAtLevel(const Target& t, int level, NormalModel normals) {
  double area = 0.0;
  std::function<void(const SubFacet&)> walk = [&](const SubFacet& f) {
    if (f.depth == level) {
      area += patchGeometry(t, f, normals).area_m2;
      return;
    }
    for (const SubFacet& c : split(t, f)) walk(c);
  };
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) walk(coarseSubFacet(t, i));
  return area;
}

TEST(Tessellation, FacetsAreWoundOutward) {
  Target t;
  t.addMaterial({});
  const Vec3 ref(0.0, -1.0, 0.0);
  addCylinder(t, {Vec3(0), Vec3(0, 0, 1), 0.5, 2.0}, 0, 16, ref);
  addSphere(t, {Vec3(3, 0, 0), 0.5}, 0, 16, ref);
  addDisk(t, {Vec3(-3, 0, 0), Vec3(0, 0, 1), 0.5}, 0, 16, ref);
  for (std::uint32_t i = 0; i < t.facetCount(); ++i) {
    const SubFacet f = coarseSubFacet(t, i);
    const PatchGeometry flat = patchGeometry(t, f, NormalModel::Flat);
    const PatchGeometry surface = patchGeometry(t, f, NormalModel::Surface);
    EXPECT_GT(glm::dot(flat.normal, surface.normal), 0.9) << "facet " << i;
  }
}

TEST(Tessellation, ChordAreaConvergesAtSecondOrder) {
  struct Case {
    const char* name;
    std::function<void(Target&)> add;
    double area;
  };
  const Vec3 ref(1, 0, 0);
  const std::vector<Case> cases = {
      {"cylinder",
       [&](Target& t) {
         addCylinder(t, {Vec3(0), Vec3(0, 0, 1), 0.5, 2.0}, 0, 16, ref);
       },
       2 * kPi * 0.5 * 2.0},
      {"sphere",
       [&](Target& t) {
         addSphere(t, {Vec3(0), 0.5}, 0, 16, ref);
       },
       4 * kPi * 0.25},
      {"disk",
       [&](Target& t) {
         addDisk(t, {Vec3(0), Vec3(0, 0, 1), 0.5}, 0, 16, ref);
       },
       kPi * 0.25},
  };
  for (const Case& c : cases) {
    Target t;
    t.addMaterial({});
    c.add(t);
    double previous_deficit = 1.0;
    for (int level = 0; level <= 5; ++level) {
      const double deficit = 1.0 - areaAtLevel(t, level, NormalModel::Flat) / c.area;
      EXPECT_GT(deficit, 0.0) << c.name << ": inscribed triangles are smaller than the surface";
      // Second-order convergence: the deficit falls about 4× per level.
      if (level > 0) {
        EXPECT_LT(deficit, 0.3 * previous_deficit) << c.name << " level " << level;
      }
      previous_deficit = deficit;
    }
    EXPECT_LT(previous_deficit, 2e-4) << c.name << " at level 5";
  }
}

TEST(Tessellation, CurvedFacetAreasConvergeAtFourthOrder) {
  // The Surface model's facet area is that of the curved patch (and a disk's rim segments are
  // included), so the total reaches the true surface area at fourth order.
  const Vec3 ref(1, 0, 0);
  Target cyl, sph, disk;
  for (Target* t : {&cyl, &sph, &disk}) t->addMaterial({});
  addCylinder(cyl, {Vec3(0), Vec3(0, 0, 1), 0.5, 2.0}, 0, 16, ref);
  addSphere(sph, {Vec3(0), 0.5}, 0, 16, ref);
  addDisk(disk, {Vec3(0), Vec3(0, 0, 1), 0.5}, 0, 16, ref);
  auto surfaceArea = [](const Target& t, int level) {
    return areaAtLevel(t, level, NormalModel::Surface);
  };
  for (const auto& [name, t, exact] :
       {std::tuple{"cylinder", &cyl, 2 * kPi * 0.5 * 2.0}, std::tuple{"sphere", &sph, kPi}}) {
    double previous = 1.0;
    for (int level = 0; level <= 4; ++level) {
      const double error = std::abs(surfaceArea(*t, level) / exact - 1.0);
      if (level > 0) {
        EXPECT_LT(error, previous / 10.0) << name << " level " << level;
      }
      previous = error;
    }
    EXPECT_LT(previous, 1e-8) << name << " at level 4";
  }
  for (int level = 0; level <= 3; ++level) {
    EXPECT_NEAR(surfaceArea(disk, level) / (kPi * 0.25), 1.0, 1e-13) << "disk level " << level;
  }
}

TEST(Tessellation, RotatesWithItsReferenceDirection) {
  // The same cylinder tessellated against two references 90° apart around its axis gives
  // the same facets rotated by 90°.
  Target a, b;
  a.addMaterial({});
  b.addMaterial({});
  addCylinder(a, {Vec3(0), Vec3(0, 0, 1), 0.5, 1.0}, 0, 8, Vec3(1, 0, 0));
  addCylinder(b, {Vec3(0), Vec3(0, 0, 1), 0.5, 1.0}, 0, 8, Vec3(0, 1, 0));
  ASSERT_EQ(a.facetCount(), b.facetCount());
  for (std::uint32_t i = 0; i < a.facetCount(); ++i) {
    for (int k = 0; k < 3; ++k) {
      const Vec3 p = a.corners_m[i][k];
      const Vec3 rotated(-p.y, p.x, p.z);
      EXPECT_NEAR(glm::length(rotated - b.corners_m[i][k]), 0.0, 1e-15) << "facet " << i;
    }
  }
}

}  // namespace
}  // namespace glint
