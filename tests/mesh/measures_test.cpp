#include "mesh/measures.h"
#include "mesh/errors.h"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include <nlohmann/json.hpp>

#include "tests/support/meshes.h"

namespace meshflow::mesh {
namespace {

using namespace meshflow::testing;

TEST(Measures, CubeIsAClosedOrientedManifoldOfVolumeOne) {
  Measures m = compute_measures(cube());
  EXPECT_EQ(m.vertices, 8u);
  EXPECT_EQ(m.triangles, 12u);
  EXPECT_EQ(m.edges, 18u);  // Euler: V - E + F = 2
  EXPECT_EQ(m.boundary_loops, 0u);
  EXPECT_EQ(m.components, 1u);
  EXPECT_DOUBLE_EQ(m.area, 6.0);
  EXPECT_DOUBLE_EQ(m.volume, 1.0);
  EXPECT_DOUBLE_EQ(m.min_angle_deg, 45.0);
  EXPECT_DOUBLE_EQ(m.max_angle_deg, 90.0);
  EXPECT_NEAR(m.average_edge_length, (12 + 6 * std::sqrt(2.0)) / 18, 1e-12);
  EXPECT_TRUE(m.is_manifold);
  EXPECT_TRUE(m.is_oriented);
  EXPECT_TRUE(m.is_orientable);
  EXPECT_TRUE(m.is_watertight);
  // 12 edges at 90 degrees between face normals (cube edges), 6 diagonals at 0.
  EXPECT_NEAR(m.average_normal_instability, 12 * 90.0 / 18, 1e-9);
}

TEST(Measures, TetrahedronByHand) {
  // Three right isosceles faces on the axis planes and one equilateral face of side sqrt(2).
  Measures m = compute_measures(tetrahedron());
  EXPECT_EQ(m.vertices, 4u);
  EXPECT_EQ(m.triangles, 4u);
  EXPECT_EQ(m.edges, 6u);
  EXPECT_EQ(m.boundary_loops, 0u);
  EXPECT_EQ(m.components, 1u);
  EXPECT_NEAR(m.min_angle_deg, 45.0, 1e-9);
  EXPECT_NEAR(m.max_angle_deg, 90.0, 1e-9);
  EXPECT_NEAR(m.average_edge_length, (3 + 3 * std::sqrt(2.0)) / 6, 1e-12);
  EXPECT_NEAR(m.area, 1.5 + std::sqrt(3.0) / 2, 1e-12);
  EXPECT_NEAR(m.volume, 1.0 / 6, 1e-12);
  // Axis edges join two axis planes (normals at 90 degrees); the other three join an axis
  // plane (outward normal -e_i) and the slanted face (normal (1,1,1)/sqrt 3): acos(-1/sqrt 3).
  double slanted = std::acos(-1 / std::sqrt(3.0)) * 180 / std::numbers::pi;
  EXPECT_NEAR(m.average_normal_instability, (3 * 90 + 3 * slanted) / 6, 1e-9);
  EXPECT_TRUE(m.is_manifold);
  EXPECT_TRUE(m.is_oriented);
  EXPECT_TRUE(m.is_orientable);
  EXPECT_TRUE(m.is_watertight);
}

TEST(Measures, InvertedTetrahedronHasNegativeVolume) {
  Mesh t = tetrahedron();
  for (auto& tri : t.triangles) std::swap(tri[1], tri[2]);
  Measures m = compute_measures(t);
  EXPECT_NEAR(m.volume, -1.0 / 6, 1e-12);
  EXPECT_TRUE(m.is_oriented);  // consistently inward is still consistent
}

TEST(Measures, OpenSquareByHand) {
  Measures m = compute_measures(open_square());
  EXPECT_EQ(m.vertices, 4u);
  EXPECT_EQ(m.triangles, 2u);
  EXPECT_EQ(m.edges, 5u);
  EXPECT_EQ(m.boundary_edges, 4u);
  EXPECT_EQ(m.boundary_loops, 1u);
  EXPECT_EQ(m.components, 1u);
  EXPECT_DOUBLE_EQ(m.min_angle_deg, 45.0);
  EXPECT_DOUBLE_EQ(m.max_angle_deg, 90.0);
  EXPECT_NEAR(m.average_edge_length, (4 + std::sqrt(2.0)) / 5, 1e-12);
  EXPECT_DOUBLE_EQ(m.area, 1.0);
  EXPECT_DOUBLE_EQ(m.volume, 0.0);                      // every point in z = 0
  EXPECT_DOUBLE_EQ(m.average_normal_instability, 0.0);  // the diagonal joins coplanar faces
  EXPECT_TRUE(m.is_manifold);
  EXPECT_TRUE(m.is_oriented);
  EXPECT_TRUE(m.is_orientable);
  EXPECT_FALSE(m.is_watertight);
}

TEST(Measures, MoebiusStripIsNotOrientable) {
  // 12 quads: 12 rungs, 24 rail edges (the boundary), 12 diagonals; V - E + F = 0.
  Measures m = compute_measures(moebius());
  EXPECT_EQ(m.vertices, 24u);
  EXPECT_EQ(m.triangles, 24u);
  EXPECT_EQ(m.edges, 48u);
  EXPECT_EQ(m.boundary_edges, 24u);
  EXPECT_EQ(m.components, 1u);
  EXPECT_EQ(m.boundary_loops, 1u);  // the strip's single edge
  EXPECT_TRUE(m.is_manifold);
  EXPECT_FALSE(m.is_orientable);
  EXPECT_FALSE(m.is_oriented);
  EXPECT_FALSE(m.is_watertight);
}

TEST(Measures, TwoCubesSharingAnEdgeAreNotManifold) {
  Measures m = compute_measures(two_cubes_sharing_an_edge());
  EXPECT_EQ(m.vertices, 14u);
  EXPECT_EQ(m.triangles, 24u);
  EXPECT_EQ(m.edges, 35u);  // 18 + 18, one shared
  EXPECT_EQ(m.components, 1u);
  EXPECT_EQ(m.boundary_loops, 0u);
  EXPECT_EQ(m.non_manifold_edges, 1u);     // four triangles on it
  EXPECT_EQ(m.non_manifold_vertices, 2u);  // its two ends
  EXPECT_DOUBLE_EQ(m.min_angle_deg, 45.0);
  EXPECT_DOUBLE_EQ(m.max_angle_deg, 90.0);
  EXPECT_NEAR(m.average_edge_length, (23 + 12 * std::sqrt(2.0)) / 35, 1e-12);
  EXPECT_DOUBLE_EQ(m.area, 12.0);
  EXPECT_DOUBLE_EQ(m.volume, 2.0);
  // Two-triangle edges only: 11 cube edges (90 degrees) and 6 diagonals (0) per cube.
  EXPECT_NEAR(m.average_normal_instability, 22 * 90.0 / 34, 1e-9);
  EXPECT_FALSE(m.is_manifold);
  EXPECT_TRUE(m.is_oriented);
  EXPECT_TRUE(m.is_orientable);
  EXPECT_FALSE(m.is_watertight);
}

TEST(Measures, BowTieVertexIsNotManifold) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {-1, 0, 0}, {-1, -1, 0}};
  m.triangles = {{0, 1, 2}, {0, 3, 4}};
  Measures r = compute_measures(m);
  EXPECT_EQ(r.non_manifold_edges, 0u);
  EXPECT_EQ(r.non_manifold_vertices, 1u);
  EXPECT_FALSE(r.is_manifold);
  EXPECT_EQ(r.components, 1u);       // connected through the shared vertex
  EXPECT_EQ(r.boundary_loops, 1u);   // the two triangles' boundaries touch at vertex 0
}

TEST(Measures, FlippedTriangleMakesMeshUnorientedButOrientable) {
  Mesh m = cube();
  std::swap(m.triangles[0][1], m.triangles[0][2]);
  Measures r = compute_measures(m);
  EXPECT_FALSE(r.is_oriented);
  EXPECT_TRUE(r.is_orientable);
  EXPECT_EQ(r.inconsistent_edges, 3u);
}

TEST(Measures, RepeatedIndexCountsAsTriangleButNotAsEdge) {
  Mesh m = open_square();
  m.triangles.push_back({0, 0, 1});
  Measures r = compute_measures(m);
  EXPECT_EQ(r.triangles, 3u);
  EXPECT_EQ(r.edges, 5u);
  EXPECT_EQ(r.degenerate_triangles, 1u);
  EXPECT_DOUBLE_EQ(r.min_angle_deg, 0.0);
}

TEST(Measures, DegenerateTrianglesHaveTheirLimitAngles) {
  // A triangle on one vertex has three 0-degree corners (not 180: no -0.0 may reach atan2);
  // a collinear one has 0, 0 and 180.
  Mesh point = open_square();
  point.triangles.push_back({2, 2, 2});
  Measures p = compute_measures(point);
  EXPECT_DOUBLE_EQ(p.min_angle_deg, 0.0);
  EXPECT_DOUBLE_EQ(p.max_angle_deg, 90.0);
  Mesh line = open_square();
  line.positions.push_back({0.5f, 0, 0});
  line.triangles.push_back({0, 4, 1});
  Measures l = compute_measures(line);
  EXPECT_DOUBLE_EQ(l.min_angle_deg, 0.0);
  EXPECT_DOUBLE_EQ(l.max_angle_deg, 180.0);
  EXPECT_EQ(l.degenerate_triangles, 1u);
}

TEST(Measures, UnreferencedVerticesAreNotComponents) {
  Mesh m = tetrahedron();
  m.positions.push_back({5, 5, 5});
  Measures r = compute_measures(m);
  EXPECT_EQ(r.vertices, 5u);
  EXPECT_EQ(r.unreferenced_vertices, 1u);
  EXPECT_EQ(r.components, 1u);
}

TEST(Measures, EmptyMeshGivesZerosAndValidJson) {
  Measures r = compute_measures(Mesh{});
  auto json = nlohmann::json::parse(measures_to_json(r));
  EXPECT_EQ(json.size(), 15u);
  EXPECT_EQ(json["NumberOfTriangles"], 0);
  EXPECT_EQ(json["MinimumAngle"], 0.0);
  EXPECT_EQ(json["IsWatertight"], false);
}

TEST(Measures, JsonHasTheFifteenOperationNamesWithTheirTypes) {
  auto json = nlohmann::json::parse(measures_to_json(compute_measures(cube())));
  ASSERT_EQ(json.size(), 15u);
  for (const auto& field : kMeasureFields) {
    ASSERT_TRUE(json.contains(field.name)) << field.name;
    switch (field.type) {
      case ValueType::Natural: EXPECT_TRUE(json[field.name].is_number_unsigned()) << field.name; break;
      case ValueType::Real: EXPECT_TRUE(json[field.name].is_number()) << field.name; break;
      case ValueType::Boolean: EXPECT_TRUE(json[field.name].is_boolean()) << field.name; break;
    }
  }
}

TEST(Measures, UnknownMeasureNameIsRejected) {
  EXPECT_THROW(measure_value(Measures{}, "NumberOfHoles"), meshflow::InvalidInput);
}

}  // namespace
}  // namespace meshflow::mesh
