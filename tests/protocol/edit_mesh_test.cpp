#include "protocol/edit_mesh.h"

#include <gtest/gtest.h>

#include "mesh/errors.h"
#include "mesh/measures.h"
#include "protocol/diff.h"
#include "tests/support/meshes.h"

namespace meshflow::protocol {
namespace {

using namespace meshflow::testing;
using mesh::Mesh;

TEST(EditMesh, AdditionsAppendAndRemovalsCompactInOrder) {
  EditMesh m(open_square());
  Index v = m.add_vertex({2, 0, 0});
  EXPECT_EQ(v, 4u);
  m.add_triangle(1, 4, 2);
  m.remove_triangle(0);
  Mesh out = m.compact();
  ASSERT_EQ(out.positions.size(), 5u);
  ASSERT_EQ(out.triangles.size(), 2u);
  EXPECT_EQ(out.triangles[0], (mesh::Triangle{0, 2, 3}));
  EXPECT_EQ(out.triangles[1], (mesh::Triangle{1, 4, 2}));
  EXPECT_EQ(apply_edits(open_square(), m.edits()), out);
}

TEST(EditMesh, RemovedVertexIsCompactedAway) {
  EditMesh m(open_square());
  m.remove_triangle(1);
  m.remove_vertex(3);
  Mesh out = m.compact();
  EXPECT_EQ(out.positions.size(), 3u);
  EXPECT_EQ(out.triangles, (std::vector<mesh::Triangle>{{0, 1, 2}}));
}

TEST(EditMesh, RemovingAUsedVertexIsRefused) {
  EditMesh m(open_square());
  EXPECT_THROW(m.remove_vertex(0), InvalidInput);
  EXPECT_EQ(m.compact(), open_square());  // nothing changed
}

TEST(EditMesh, SplitTriangleAtItsCentre) {
  EditMesh m(open_square());
  Index c = m.split_triangle(0);
  Mesh out = m.compact();
  EXPECT_EQ(out.positions[c], (mesh::Point{2.0f / 3, 1.0f / 3, 0}));
  EXPECT_EQ(out.triangles.size(), 4u);
  EXPECT_DOUBLE_EQ(mesh::compute_measures(out).area, 1.0);
}

TEST(EditMesh, SwapEdgeKeepsOrientationAndArea) {
  EditMesh m(open_square());
  m.swap_edge(0, 2);
  Mesh out = m.compact();
  EXPECT_EQ(out.triangles, (std::vector<mesh::Triangle>{{0, 1, 3}, {1, 2, 3}}));
  auto s = mesh::compute_measures(out);
  EXPECT_TRUE(s.is_oriented);
  EXPECT_DOUBLE_EQ(s.area, 1.0);
}

TEST(EditMesh, AddEdgeNamesTheNewDiagonal) {
  EditMesh a(open_square()), b(open_square());
  a.add_edge(1, 3);
  b.swap_edge(0, 2);
  EXPECT_EQ(a.compact(), b.compact());
}

TEST(EditMesh, CollapseEdgeMergesTheSecondVertexIntoTheFirst) {
  EditMesh m(cube());
  m.collapse_edge(0, 1, mesh::Point{0.5f, 0, 0});
  Mesh out = m.compact();
  EXPECT_EQ(out.positions.size(), 7u);
  EXPECT_EQ(out.triangles.size(), 10u);
  EXPECT_EQ(out.positions[0], (mesh::Point{0.5f, 0, 0}));
  auto s = mesh::compute_measures(out);
  EXPECT_TRUE(s.is_watertight);
  EXPECT_TRUE(s.is_oriented);
}

TEST(EditMesh, SplitEdgeSplitsBothTriangles) {
  EditMesh m(open_square());
  Index mid = m.split_edge(0, 2);
  Mesh out = m.compact();
  EXPECT_EQ(out.triangles.size(), 4u);
  EXPECT_EQ(out.positions[mid], (mesh::Point{0.5f, 0.5f, 0}));
  EXPECT_TRUE(mesh::compute_measures(out).is_oriented);
}

TEST(EditMesh, MoveAllAndClearAll) {
  EditMesh m(open_square());
  std::vector<mesh::Point> moved = open_square().positions;
  for (auto& p : moved) p[2] = 1;
  m.move_all_vertices(moved);
  EXPECT_EQ(m.compact().positions, moved);
  EXPECT_THROW(m.move_all_vertices({{0, 0, 0}}), InvalidInput);
  m.clear_all();
  EXPECT_TRUE(m.compact().empty());
}

TEST(EditMesh, BadEditsNameTheirIndex) {
  EditList edits{RemoveTriangle{0}, RemoveTriangle{0}};
  try {
    apply_edits(open_square(), edits);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("edit 1: RemoveTriangle 0: triangle was removed"), std::string::npos) << e.what();
  }
  EXPECT_THROW(apply_edits(open_square(), {SwapEdge{0, 1}}), InvalidInput);  // a boundary edge
  EXPECT_THROW(apply_edits(open_square(), {AddTriangle{0, 1, 9}}), InvalidInput);
}

TEST(Diff, ReproducesTheTargetExactlyInEveryCase) {
  Mesh a = cube();
  std::vector<Mesh> targets;
  Mesh moved = a;
  moved.positions[3][0] += 0.25f;
  targets.push_back(moved);
  Mesh fewer = a;
  fewer.triangles.erase(fewer.triangles.begin() + 5);
  targets.push_back(fewer);
  Mesh more = a;
  more.positions.push_back({3, 3, 3});
  more.triangles.push_back({0, 1, 8});
  targets.push_back(more);
  Mesh reordered = a;
  std::reverse(reordered.triangles.begin(), reordered.triangles.end());
  targets.push_back(reordered);
  targets.push_back(Mesh{});
  targets.push_back(tetrahedron());
  for (const Mesh& b : targets) EXPECT_EQ(apply_edits(a, diff_meshes(a, b)), b);
}

}  // namespace
}  // namespace meshflow::protocol
