#include "mesh/generate.h"

#include <gtest/gtest.h>

#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "tests/support/meshes.h"

namespace meshflow::mesh {
namespace {

using namespace meshflow::testing;

TEST(Generate, TerrainIsOneManifoldSheetWithOneBoundary) {
  TempDir dir;
  GenerateResult r = generate_mesh({.shape = Shape::Terrain, .triangles = 20000}, dir.file("t.ply"));
  Mesh m = read_mesh(dir.file("t.ply"));
  Measures s = compute_measures(m);
  EXPECT_EQ(s.triangles, r.triangles);
  EXPECT_EQ(s.vertices, r.vertices);
  EXPECT_NEAR(double(r.triangles), 20000, 400);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.boundary_loops, 1u);
  EXPECT_TRUE(s.is_manifold);
  EXPECT_TRUE(s.is_oriented);
  EXPECT_EQ(s.degenerate_triangles, 0u);
}

TEST(Generate, SphereIsWatertightAndOutward) {
  TempDir dir;
  GenerateResult r = generate_mesh({.shape = Shape::Sphere, .triangles = 20000}, dir.file("s.ply"));
  Measures s = compute_measures(read_mesh(dir.file("s.ply")));
  EXPECT_EQ(s.triangles, r.triangles);
  EXPECT_EQ(s.components, 1u);
  EXPECT_EQ(s.boundary_loops, 0u);
  EXPECT_TRUE(s.is_watertight);
  EXPECT_TRUE(s.is_oriented);
  EXPECT_GT(s.volume, 0);  // outward normals
}

TEST(Generate, SameSeedSameBytesOtherSeedOtherMesh) {
  TempDir dir;
  generate_mesh({.shape = Shape::Terrain, .triangles = 5000, .seed = 7}, dir.file("a.ply"));
  generate_mesh({.shape = Shape::Terrain, .triangles = 5000, .seed = 7}, dir.file("b.ply"));
  generate_mesh({.shape = Shape::Terrain, .triangles = 5000, .seed = 8}, dir.file("c.ply"));
  EXPECT_EQ(read_mesh(dir.file("a.ply")), read_mesh(dir.file("b.ply")));
  EXPECT_NE(read_mesh(dir.file("a.ply")), read_mesh(dir.file("c.ply")));
}

TEST(Generate, TooFewTrianglesIsRefused) {
  TempDir dir;
  EXPECT_THROW(generate_mesh({.triangles = 1}, dir.file("x.ply")), meshflow::InvalidInput);
}

}  // namespace
}  // namespace meshflow::mesh
