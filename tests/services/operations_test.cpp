#include "services/operation.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>

#include <nlohmann/json.hpp>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "protocol/correction.h"
#include "protocol/edit_mesh.h"
#include "services/compare.h"
#include "tests/support/manifest.h"
#include "tests/support/meshes.h"

namespace meshflow::services {
namespace {

using namespace meshflow::testing;
using mesh::Mesh;

Mesh shared(const std::string& name) { return mesh::read_mesh(shared_meshes() + "/" + name); }

AtomicResult run(const std::string& op, const Mesh& m, std::map<std::string, std::string> given = {}) {
  const OperationSpec& spec = find_operation(op);
  return run_atomic(spec, m, resolve_params(spec, given));
}

TEST(Operations, RemoveSmallestComponentsKeepsOne) {
  Mesh tank = shared("defects/tank_many_components.ply");
  auto before = mesh::compute_measures(tank);
  AtomicResult r = run("RemoveSmallestComponents", tank);
  auto after = mesh::compute_measures(r.output);
  EXPECT_GT(before.components, 1000u);
  EXPECT_EQ(after.components, 1u);
  EXPECT_EQ(after.unreferenced_vertices, 0u);
  EXPECT_LT(after.triangles, before.triangles);
}

TEST(Operations, FillHolesClosesTheBunny) {
  Mesh bunny = shared("real/stanford-bunny.obj");
  AtomicResult r = run("FillHoles", bunny);
  auto after = mesh::compute_measures(r.output);
  EXPECT_EQ(after.boundary_loops, 0u);
  EXPECT_TRUE(after.is_watertight);
  EXPECT_GT(after.triangles, bunny.triangles.size());
}

// A 60 x 60 height field with a 4 x 4 hole: CGAL only sees a few rings around the two
// loops; the cut around that neighbourhood must not be taken for a hole.
TEST(Operations, FillHolesPatchesOnlyTrueLoopsOfALargeMesh) {
  Mesh grid;
  const int n = 60;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) grid.positions.push_back({float(i), float(j), 0.1f * float((i * 7 + j * 3) % 5)});
  auto id = [&](int i, int j) { return static_cast<mesh::Index>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      if (i >= 28 && i < 32 && j >= 28 && j < 32) continue;
      grid.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      grid.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
  AtomicResult kept = run("FillHolesHeightField", grid);
  auto m = mesh::compute_measures(kept.output);
  EXPECT_EQ(m.boundary_loops, 1u);
  EXPECT_TRUE(m.is_manifold);
  EXPECT_GT(kept.output.triangles.size(), grid.triangles.size());
  EXPECT_LT(kept.output.triangles.size(), grid.triangles.size() + 200);  // one small patch
  // The untouched part is kept as it was, in order.
  EXPECT_TRUE(std::equal(grid.triangles.begin(), grid.triangles.end(), kept.output.triangles.begin()));
  EXPECT_EQ(mesh::compute_measures(run("FillHoles", grid).output).boundary_loops, 0u);
}

TEST(Operations, FillHolesHeightFieldKeepsTheLargestLoop) {
  Mesh holes = shared("defects/elephant-with-holes.off");
  AtomicResult r = run("FillHolesHeightField", holes);
  EXPECT_EQ(mesh::compute_measures(r.output).boundary_loops, 1u);
}

TEST(Operations, RemoveDegenerateTrianglesLeavesNoZeroArea) {
  for (const char* name : {"defects/degtri_sliding.off", "malformed/elephant_degenerate.off", "real/ogre.obj"}) {
    SCOPED_TRACE(name);
    Mesh m = shared(name);
    AtomicResult r = run("RemoveDegenerateTriangles", m);
    auto after = mesh::compute_measures(r.output);
    EXPECT_EQ(after.degenerate_triangles, 0u);
    EXPECT_GT(after.min_angle_deg, 0.0);
    // No hole opened: zero-area triangles are edited away, not deleted.
    EXPECT_LE(after.boundary_loops, mesh::compute_measures(m).boundary_loops);
  }
}

TEST(Operations, LaplacianSmoothingLowersNoiseAndKeepsBoundaries) {
  Mesh bunny = shared("real/stanford-bunny.obj");
  AtomicResult noisy = run("AddNoise", bunny, {{"maxDistance", "0.2"}, {"seed", "3"}});
  AtomicResult smooth = run("LaplacianSmoothing", noisy.output, {{"iterations", "3"}});
  auto n = mesh::compute_measures(noisy.output), s = mesh::compute_measures(smooth.output);
  EXPECT_GT(n.average_normal_instability, mesh::compute_measures(bunny).average_normal_instability);
  EXPECT_LT(s.average_normal_instability, n.average_normal_instability);
  EXPECT_EQ(s.boundary_loops, n.boundary_loops);
  EXPECT_EQ(smooth.output.positions.size(), bunny.positions.size());
}

TEST(Operations, DuplicatesDoubledBackOnAnEdgeGoTogether) {
  // A triangle and its reverse hanging from an edge of a square: removing one copy would leave
  // the other's two free edges open; removing both leaves the square as it was.
  Mesh m = open_square();
  m.positions.push_back({0.5f, 0.5f, 1});
  m.triangles.push_back({0, 1, 4});
  m.triangles.push_back({0, 4, 1});
  AtomicResult r = run("RemoveDegenerateTriangles", m);
  EXPECT_EQ(r.output.triangles, open_square().triangles);
  // A plain duplicate inside a surface keeps one copy.
  Mesh cube_twice = cube();
  cube_twice.triangles.push_back(cube_twice.triangles[3]);
  EXPECT_EQ(run("RemoveDegenerateTriangles", cube_twice).output, cube());
}

TEST(Operations, AddNoiseIsReproducibleAndBounded) {
  Mesh kitten = shared("real/kitten.off");
  AtomicResult a = run("AddNoise", kitten, {{"maxDistance", "0.5"}, {"seed", "11"}});
  AtomicResult b = run("AddNoise", kitten, {{"maxDistance", "0.5"}, {"seed", "11"}});
  AtomicResult c = run("AddNoise", kitten, {{"maxDistance", "0.5"}, {"seed", "12"}});
  EXPECT_EQ(a.output, b.output);
  EXPECT_NE(a.output, c.output);
  double limit = 0.005 * mesh::bounding_box(kitten).diagonal() * 1.0001;
  for (std::size_t v = 0; v < kitten.positions.size(); ++v) {
    double d = 0;
    for (int k = 0; k < 3; ++k) d += std::pow(double(a.output.positions[v][k]) - kitten.positions[v][k], 2);
    EXPECT_LE(std::sqrt(d), limit);
  }
}

TEST(Operations, SimplifyMeetsTheVertexTargetAndTheErrorBound) {
  Mesh kitten = shared("real/kitten.off");
  AtomicResult t = run("Simplify", kitten, {{"targetVertices", "500"}});
  EXPECT_EQ(t.output.positions.size(), 500u);
  AtomicResult e = run("Simplify", kitten, {{"maxError", "0.5"}});
  auto s = mesh::compute_measures(e.output);
  EXPECT_LT(s.vertices, kitten.positions.size() / 2);
  EXPECT_TRUE(s.is_watertight);
  CompareResult c = compare(kitten, e.output);
  EXPECT_LT(c.mean_ab, 0.5);
}

TEST(Operations, BadParametersAreRefusedClearly) {
  const OperationSpec& ls = find_operation("LaplacianSmoothing");
  auto message = [](auto&& f) {
    try {
      f();
    } catch (const InvalidInput& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message([&] { resolve_params(ls, {{"iterations", "-1"}}); }).find("iterations=-1: must be >= 1"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(ls, {{"iterations", "1.5"}}); }).find("whole number"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(find_operation("Simplify"), {{"maxError", "0"}}); }).find("must be > 0"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(ls, {{"iters", "2"}}); }).find("has no parameter 'iters'"), std::string::npos);
  EXPECT_NE(message([&] { find_operation("Smooth"); }).find("unknown operation 'Smooth' (known: "), std::string::npos);
  const OperationSpec& simplify = find_operation("Simplify");
  const OperationSpec& noise = find_operation("AddNoise");
  EXPECT_NE(message([&] { resolve_params(ls, {{"iterations", "0"}}); }).find("iterations=0: must be >= 1"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(ls, {{"iterations", "abc"}}); }).find("expected a natural number"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(ls, {{"iterations", ""}}); }).find("expected a natural number"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(simplify, {{"maxError", "-0.5"}}); }).find("maxError=-0.5: must be > 0"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(simplify, {{"targetVertices", "-3"}}); }).find("must be >= 0"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(simplify, {{"targetVertices", "1e12"}}); }).find("must be <= 4294967295"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(noise, {{"maxDistance", "nan"}}); }).find("expected a real number"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(noise, {{"maxDistance", "inf"}}); }).find("expected a real number"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(noise, {{"maxDistance", "0"}}); }).find("must be > 0"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(noise, {{"seed", "-1"}}); }).find("seed=-1: must be >= 0"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(noise, {{"seed", "1e300"}}); }).find("must be <= 9007199254740992"), std::string::npos);
  EXPECT_NE(message([&] { resolve_params(find_operation("FillHoles"), {{"iterations", "1"}}); }).find("it takes none"), std::string::npos);
  EXPECT_NE(message([&] { run_atomic(ls, cube(), {{"iterations", -2}}); }).find("iterations must be at least 1"), std::string::npos);
  EXPECT_THROW(run_analysis(ls, cube()), InvalidInput);
}

TEST(Operations, EveryMeasureIsAnAnalysisOperation) {
  for (const auto& field : mesh::kMeasureFields) {
    const OperationSpec& spec = find_operation(field.name);
    EXPECT_EQ(spec.kind, OperationKind::Analysis);
    EXPECT_EQ(spec.value_type, field.type);
  }
  EXPECT_EQ(run_analysis(find_operation("NumberOfEdges"), cube()), 18);
  auto json = operations_to_json();
  EXPECT_EQ(json.size(), 7u + 15u);
}

// Vertices on an edge used by exactly one triangle.
std::vector<bool> boundary_vertices(const Mesh& m) {
  std::map<std::pair<mesh::Index, mesh::Index>, int> uses;
  for (const auto& t : m.triangles)
    for (int k = 0; k < 3; ++k)
      if (t[k] != t[(k + 1) % 3]) uses[std::minmax(t[k], t[(k + 1) % 3])]++;
  std::vector<bool> out(m.positions.size(), false);
  for (const auto& [edge, n] : uses)
    if (n == 1) out[edge.first] = out[edge.second] = true;
  return out;
}

// Every atomic operation on every valid mesh of the shared corpus: its effect, checked by the
// measures, and its correction, which must reproduce the output bit for bit.
TEST(Operations, EveryOperationOnEveryMeshHasItsEffectAndItsCorrection) {
  const std::vector<std::pair<std::string, std::map<std::string, std::string>>> ops = {
      {"RemoveSmallestComponents", {}},
      {"LaplacianSmoothing", {{"iterations", "2"}}},
      {"AddNoise", {{"maxDistance", "0.3"}, {"seed", "5"}}},
      {"RemoveDegenerateTriangles", {}},
      {"FillHolesHeightField", {}},
      {"FillHoles", {}},
      {"Simplify", {{"maxError", "0.2"}}},
  };
  auto meshes = valid_shared_meshes();
  ASSERT_GE(meshes.size(), 39u);
  for (const std::string& name : meshes) {
    Mesh input = shared(name);
    auto before = mesh::compute_measures(input);
    std::vector<bool> on_boundary = boundary_vertices(input);
    for (const auto& [op, params] : ops) {
      // Filling the outer border of a 500k-triangle terrain is a different job; skip it there.
      if (op == "FillHoles" && input.triangles.size() > 200000) continue;
      SCOPED_TRACE(name + " " + op);
      AtomicResult r = run(op, input, params);
      auto after = mesh::compute_measures(r.output);
      if (op == "RemoveSmallestComponents") {
        EXPECT_EQ(after.components, std::min<std::uint64_t>(before.components, 1));
        EXPECT_EQ(after.unreferenced_vertices, 0u);
        EXPECT_LE(after.boundary_loops, before.boundary_loops);
      } else if (op == "LaplacianSmoothing") {
        ASSERT_EQ(r.output.positions.size(), input.positions.size());
        EXPECT_EQ(r.output.triangles, input.triangles);
        std::size_t moved_on_boundary = 0;
        for (std::size_t v = 0; v < input.positions.size(); ++v)
          moved_on_boundary += on_boundary[v] && r.output.positions[v] != input.positions[v];
        EXPECT_EQ(moved_on_boundary, 0u);
      } else if (op == "AddNoise") {
        ASSERT_EQ(r.output.positions.size(), input.positions.size());
        EXPECT_EQ(r.output.triangles, input.triangles);
        double limit = 0.003 * mesh::bounding_box(input).diagonal() * 1.0001;
        double largest = 0;
        for (std::size_t v = 0; v < input.positions.size(); ++v) {
          double d = 0;
          for (int k = 0; k < 3; ++k) d += std::pow(double(r.output.positions[v][k]) - input.positions[v][k], 2);
          largest = std::max(largest, std::sqrt(d));
        }
        EXPECT_LE(largest, limit);
      } else if (op == "RemoveDegenerateTriangles") {
        EXPECT_EQ(after.degenerate_triangles, 0u);
        EXPECT_LE(after.boundary_loops, before.boundary_loops);  // zero-area triangles are edited away, not deleted
      } else if (op == "FillHolesHeightField") {
        EXPECT_EQ(after.boundary_loops, std::min<std::uint64_t>(before.boundary_loops, 1));
      } else if (op == "FillHoles") {
        EXPECT_EQ(after.boundary_loops, 0u);
      } else if (op == "Simplify") {
        EXPECT_LE(after.vertices, before.vertices);
      }
      auto bytes = protocol::encode_correction(input, mesh::mesh_sha256(input), mesh::mesh_sha256(r.output), r.edits);
      EXPECT_EQ(mesh::mesh_sha256(protocol::apply_correction(input, bytes)), mesh::mesh_sha256(r.output));
    }
  }
}

TEST(Compare, IdenticalMeshesAreAtDistanceZeroAndAShiftIsMeasured) {
  Mesh kitten = shared("real/kitten.off");
  CompareResult same = compare(kitten, kitten);
  EXPECT_NEAR(same.mean_ab, 0, 1e-6);
  EXPECT_NEAR(same.max_ba, 0, 1e-6);
  Mesh shifted = cube();
  for (auto& p : shifted.positions) p[2] += 0.1f;  // 0.1 / sqrt(3) of the diagonal
  CompareResult c = compare(cube(), shifted);
  EXPECT_NEAR(c.max_ab, 100 * 0.1 / std::sqrt(3.0), 0.01);
  EXPECT_GT(c.mean_ab, 0);
}

TEST(Compare, OneWayStreamsTheFirstMeshAndMeasuresItsVertices) {
  meshflow::testing::TempDir dir;
  Mesh shifted = cube();
  for (auto& p : shifted.positions) p[2] += 0.1f;
  mesh::write_mesh(shifted, dir.file("shifted.ply"));
  CompareResult c = compare_one_way(dir.file("shifted.ply"), cube());
  EXPECT_TRUE(c.one_way);
  EXPECT_EQ(c.samples_a, 8u);
  // The top corners are 0.1 above the cube, the bottom ones on its sides; the diagonal is sqrt(3).
  EXPECT_NEAR(c.max_ab, 100 * 0.1 / std::sqrt(3.0), 1e-4);
  EXPECT_NEAR(c.mean_ab, 100 * 0.05 / std::sqrt(3.0), 1e-4);
  EXPECT_NE(c.to_json().find("\"one_way\": true"), std::string::npos);

  const std::string kitten_path = meshflow::testing::shared_meshes() + "/real/kitten.off";
  Mesh kitten = mesh::read_mesh(kitten_path);
  CompareResult same = compare_one_way(kitten_path, kitten, {.max_samples = 500});
  EXPECT_NEAR(same.mean_ab, 0, 1e-6);
  EXPECT_GT(same.samples_a, 250u);  // about 1 in ceil(V / 500) of the vertices, chosen by hash
  EXPECT_LE(same.samples_a, 1000u);
  EXPECT_THROW(compare_one_way(dir.file("missing.ply"), kitten), std::exception);
}

}  // namespace
}  // namespace meshflow::services
