#include "services/simplify.h"

#include <gtest/gtest.h>

#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "services/compare.h"
#include "tests/support/meshes.h"

namespace meshflow::services {
namespace {

using namespace meshflow::testing;
using mesh::Mesh;

// Triangle normals before and after agree in sign over the surface: no flipped triangle.
TEST(Simplify, KeepsTopologyManifoldnessAndOrientation) {
  for (const char* name : {"real/kitten.off", "real/stanford-bunny.obj", "large/terrain_fuji_512.ply"}) {
    SCOPED_TRACE(name);
    Mesh input = mesh::read_mesh(shared_meshes() + "/" + name);
    auto before = mesh::compute_measures(input);
    double diagonal = mesh::bounding_box(input).diagonal();
    SimplifyResult r = simplify(input, {.max_error = 0.001 * diagonal});
    auto after = mesh::compute_measures(r.output);
    EXPECT_LT(after.vertices, before.vertices);
    EXPECT_EQ(after.components, before.components);
    EXPECT_EQ(after.boundary_loops, before.boundary_loops);
    EXPECT_EQ(after.is_manifold, before.is_manifold);
    EXPECT_TRUE(after.is_oriented);
    EXPECT_EQ(after.degenerate_triangles, 0u);
    EXPECT_LE(r.max_rms_error, 0.001 * diagonal);
    CompareResult c = compare(input, r.output, {.min_samples = 20000, .max_samples = 200000});
    EXPECT_LT(c.mean_ab, 0.1);  // mean distance well under the 0.1 % RMS bound
  }
}

TEST(Simplify, FlatPartsDecimateMoreThanDetailedOnes) {
  // A terrain that is flat on its left half and bumpy on its right half.
  Mesh m;
  const int n = 60;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      float x = float(i) / n, y = float(j) / n;
      float z = x < 0.5f ? 0.0f : 0.05f * std::sin(40 * x) * std::cos(40 * y);
      m.positions.push_back({x, y, z});
    }
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      mesh::Index a = j * (n + 1) + i;
      m.triangles.push_back({a, a + 1, a + n + 2});
      m.triangles.push_back({a, a + n + 2, a + n + 1});
    }
  SimplifyResult r = simplify(m, {.max_error = 0.002});
  int left = 0, right = 0;
  for (const auto& p : r.output.positions) (p[0] < 0.45f ? left : right)++;
  EXPECT_LT(left * 4, right);
}

// The max-error stop gives the mesh a vertex budget; it must spend it as well as ranking by
// quadric error to that many vertices does (the peers' way). With the RMS bound alone the scans
// lost 4-11 % here (bench/README.md), the bunny at 0.05 % of the diagonal 6 %.
TEST(Simplify, AMaxErrorStopIsAsGoodAsAVertexTargetAtItsCount) {
  Mesh input = mesh::read_mesh(shared_meshes() + "/real/stanford-bunny.obj");
  double max_error = 0.0005 * mesh::bounding_box(input).diagonal();
  SimplifyResult by_error = simplify(input, {.max_error = max_error});
  EXPECT_LE(by_error.max_rms_error, max_error);
  SimplifyResult by_count = simplify(input, {.target_vertices = by_error.output.positions.size()});
  CompareParams samples{.min_samples = 50000, .max_samples = 200000};
  auto mean = [&](const Mesh& m) {
    CompareResult c = compare(input, m, samples);
    return (c.mean_ab + c.mean_ba) / 2;
  };
  EXPECT_LE(mean(by_error.output), 1.02 * mean(by_count.output));
}

TEST(Simplify, HitsTheVertexTarget) {
  Mesh bunny = mesh::read_mesh(shared_meshes() + "/real/stanford-bunny.obj");
  SimplifyResult r = simplify(bunny, {.target_vertices = 5000});
  EXPECT_EQ(r.output.positions.size(), 5000u);
  EXPECT_EQ(mesh::compute_measures(r.output).boundary_loops, 5u);
}

TEST(Simplify, NeedsAStoppingRule) {
  EXPECT_THROW(simplify(cube(), {}), InvalidInput);
}

}  // namespace
}  // namespace meshflow::services
