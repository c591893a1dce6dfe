#include "parallel/distributed_simplify.h"

#include <gtest/gtest.h>

#include <filesystem>

#include "mesh/errors.h"
#include "mesh/generate.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "mesh/part_files.h"
#include "parallel/bsp_partition.h"
#include "services/compare.h"
#include "services/simplify.h"
#include "tests/support/meshes.h"

namespace meshflow::parallel {
namespace {

using mesh::Mesh;

Mesh generated(mesh::Shape shape, std::uint64_t triangles) {
  meshflow::testing::TempDir dir;
  mesh::GenerateParams g;
  g.shape = shape;
  g.triangles = triangles;
  mesh::generate_mesh(g, dir.file("m.ply"));
  return mesh::read_mesh(dir.file("m.ply"));
}

TEST(BspPartition, CellsCoverEveryVertexAndStayNearTheLimit) {
  Mesh m = generated(mesh::Shape::Terrain, 100000);
  BspPartition p = bsp_partition(m, 5000);
  EXPECT_GE(p.cells, m.positions.size() / 5000);
  std::vector<std::size_t> count(p.cells, 0);
  for (auto c : p.cell_of_vertex) {
    ASSERT_LT(c, p.cells);
    count[c]++;
  }
  for (std::size_t c = 0; c < p.cells; ++c) {
    EXPECT_GT(count[c], 0u);
    EXPECT_LE(count[c], 5000u * 3 / 2);  // estimated from a sample: allow 50 %
  }
  EXPECT_THROW(bsp_partition(m, 0), InvalidInput);
}

// The guarantees of issue 7 against a single-node simplification of the same input: same
// components and boundary loops (no crack), manifold, watertight when the input is, error
// within 5 %, vertex count within 10 %, and the same result whatever the number of workers.
TEST(DistributedSimplify, MatchesSingleNodeWithoutCracks) {
  for (mesh::Shape shape : {mesh::Shape::Terrain, mesh::Shape::Sphere}) {
    SCOPED_TRACE(shape == mesh::Shape::Sphere ? "sphere" : "terrain");
    Mesh input = generated(shape, 80000);
    double max_error = 0.0005 * mesh::bounding_box(input).diagonal();
    Mesh single = services::simplify(input, {.max_error = max_error}).output;
    auto s = mesh::compute_measures(single);
    double single_error = services::compare(input, single).mean_ab;
    Mesh first;
    for (unsigned workers : {1u, 3u}) {
      meshflow::testing::TempDir dir;
      DistributedReport report;
      DistributedParams params;
      params.max_error = max_error, params.vertices_per_part = 4000, params.workers = workers, params.parts_dir = dir.file("parts");
      Mesh out = simplify_distributed(input, params, report);
      EXPECT_GE(report.parts, 8u);
      EXPECT_GT(report.seam_vertices, 0u);
      auto d = mesh::compute_measures(out);
      EXPECT_EQ(d.components, s.components);
      EXPECT_EQ(d.boundary_loops, s.boundary_loops);
      EXPECT_TRUE(d.is_manifold);
      EXPECT_EQ(d.is_watertight, s.is_watertight);
      EXPECT_EQ(d.degenerate_triangles, 0u);
      EXPECT_LE(services::compare(input, out).mean_ab, 1.05 * single_error);
      EXPECT_NEAR(double(d.vertices) / double(s.vertices), 1.0, 0.1);
      if (first.empty()) first = out;
      else EXPECT_TRUE(out == first) << "the result depends on the number of workers";
    }
  }
}

TEST(DistributedSimplify, RefusesBadInput) {
  Mesh m;
  m.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  m.triangles = {{0, 1, 7}};
  meshflow::testing::TempDir dir;
  DistributedReport report;
  DistributedParams params;
  params.max_error = 0.1, params.parts_dir = dir.file("parts");
  EXPECT_THROW(simplify_distributed(m, params, report), InvalidInput);  // vertex 7 of 3
  m.triangles = {{0, 1, 2}};
  params.max_error = 0;
  EXPECT_THROW(simplify_distributed(m, params, report), InvalidInput);
  params.max_error = 0.1, params.workers = 0;
  EXPECT_THROW(simplify_distributed(m, params, report), InvalidInput);
  // A damaged part file is refused with its name and byte offset.
  params.workers = 1;
  ASSERT_EQ(partition_to_files(m, 10, params.parts_dir, report), 1u);
  std::filesystem::resize_file(params.parts_dir + "/part-0.mfp", 30);
  try {
    simplify_part_files(params.parts_dir, 1, params, report);
    FAIL() << "a truncated part file was accepted";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("part-0.mfp: byte"), std::string::npos) << e.what();
  }
}

TEST(IndependentSets, NoTwoAdjacentPartsTogetherAndEveryPartOnce) {
  Mesh m = generated(mesh::Shape::Sphere, 40000);
  meshflow::testing::TempDir dir;
  DistributedReport report;
  std::size_t parts = partition_to_files(m, 1500, dir.file("parts"), report);
  ASSERT_GE(parts, 8u);
  for (std::size_t max_set : {1u, 2u, 4u}) {
    auto sets = independent_sets(report.adjacency, max_set);
    std::vector<int> seen(parts, 0);
    for (const auto& set : sets) {
      EXPECT_LE(set.size(), max_set);
      for (auto a : set) {
        seen[a]++;
        for (auto b : set)
          EXPECT_FALSE(std::binary_search(report.adjacency[a].begin(), report.adjacency[a].end(), b));
      }
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), 1), static_cast<long>(parts));
  }
  EXPECT_THROW(independent_sets(report.adjacency, 0), InvalidInput);
}

TEST(PartFiles, RoundTripAndRefuseDamage) {
  mesh::PartFile part;
  part.global_ids = {3, 9, 12};
  part.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  part.shared = {1, 0, 1};
  part.triangles = {{0, 1, 2}};
  auto bytes = mesh::encode_part(part);
  mesh::PartFile back = mesh::decode_part(bytes, "p.mfp");
  EXPECT_EQ(back.global_ids, part.global_ids);
  EXPECT_EQ(back.positions, part.positions);
  EXPECT_EQ(back.triangles, part.triangles);
  part.quadrics.assign(3, {1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11});
  EXPECT_EQ(mesh::decode_part(mesh::encode_part(part), "p.mfp").quadrics, part.quadrics);
  bytes.back() = 7;  // a corner past the three vertices
  EXPECT_THROW(mesh::decode_part(bytes, "p.mfp"), ParseError);
  bytes.resize(bytes.size() - 1);
  EXPECT_THROW(mesh::decode_part(bytes, "p.mfp"), ParseError);
  bytes[0] = 'X';
  EXPECT_THROW(mesh::decode_part(bytes, "p.mfp"), ParseError);
  // Found by fuzz_part: an empty part with the quadric flag set would not encode back the same.
  std::vector<std::uint8_t> empty_with_flag = mesh::encode_part(mesh::PartFile{});
  empty_with_flag.back() = 1;
  EXPECT_THROW(mesh::decode_part(empty_with_flag, "p.mfp"), ParseError);
}

}  // namespace
}  // namespace meshflow::parallel
