#include "protocol/correction.h"

#include <gtest/gtest.h>

#include <map>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "protocol/edit_mesh.h"
#include "tests/support/meshes.h"

namespace meshflow::protocol {
namespace {

using namespace meshflow::testing;
using mesh::Mesh;

struct Example {
  Mesh base, result;
  EditList edits;
  std::vector<std::uint8_t> bytes;
};

Example every_edit_kind() {
  Example x;
  x.base = cube();
  EditMesh m(x.base);
  m.move_vertex(7, {1.25f, 1, 1});
  m.split_triangle(0);
  m.split_triangle(1, mesh::Point{0.7f, 0.7f, 0});
  m.split_edge(4, 5);
  m.collapse_edge(4, 8, mesh::Point{0.5f, 0.5f, 0});
  Index v = m.add_vertex({-1, -1, -1});
  m.add_triangle(0, 4, v);
  m.remove_triangle(m.triangle_slots() - 1);
  m.remove_vertex(v);
  std::vector<mesh::Point> all;
  for (std::size_t i = 0; i < m.vertex_slots(); ++i)
    if (m.vertex_alive(static_cast<Index>(i))) all.push_back(m.position(static_cast<Index>(i)));
  all[1][1] += 1e-3f;
  m.move_all_vertices(all);
  x.result = m.compact();
  x.edits = m.edits();
  x.bytes = encode_correction(x.base, mesh::mesh_sha256(x.base), mesh::mesh_sha256(x.result), x.edits);
  return x;
}

TEST(Correction, RoundTripGivesTheResultBitForBit) {
  Example x = every_edit_kind();
  Mesh patched = apply_correction(x.base, x.bytes);
  EXPECT_EQ(mesh::mesh_sha256(patched), mesh::mesh_sha256(x.result));
  EXPECT_EQ(decode_correction(x.base, x.bytes).size(), x.edits.size());
  CorrectionHeader header = read_correction_header(x.bytes);
  EXPECT_EQ(header.base_sha256, mesh::mesh_sha256(x.base));
  EXPECT_EQ(header.edit_count, x.edits.size());
}

TEST(Correction, EncodingIsDeterministic) {
  EXPECT_EQ(every_edit_kind().bytes, every_edit_kind().bytes);
}

TEST(Correction, WrongBaseIsRefusedBeforeAnything) {
  Example x = every_edit_kind();
  try {
    apply_correction(tetrahedron(), x.bytes);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("correction applies to the mesh with SHA-256"), std::string::npos);
  }
}

TEST(Correction, WrongPromisedResultIsRefused) {
  Example x = every_edit_kind();
  auto bytes = encode_correction(x.base, mesh::mesh_sha256(x.base), mesh::mesh_sha256(x.base), x.edits);
  try {
    apply_correction(x.base, bytes);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("but the correction promises"), std::string::npos);
  }
}

TEST(Correction, DecoderRejectsDamagedFiles) {
  Example x = every_edit_kind();
  auto expect_refused = [&](std::vector<std::uint8_t> bytes, const char* phrase) {
    try {
      apply_correction(x.base, bytes);
      ADD_FAILURE() << "accepted; expected " << phrase;
    } catch (const InvalidInput& e) {
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  };
  auto bad_magic = x.bytes;
  bad_magic[0] = 'X';
  expect_refused(bad_magic, "bad magic");
  auto bad_version = x.bytes;
  bad_version[4] = 9;
  expect_refused(bad_version, "unknown version 9");
  expect_refused(std::vector<std::uint8_t>(x.bytes.begin(), x.bytes.begin() + 40), "truncated header");
  expect_refused(std::vector<std::uint8_t>(x.bytes.begin(), x.bytes.end() - 5), "truncated or corrupt");
  auto trailing = x.bytes;
  trailing.push_back(0);
  expect_refused(trailing, "trailing bytes");
  expect_refused({}, "truncated header");
}

TEST(Correction, SmallMovesCostLittle) {
  // Laplacian-like small moves of every vertex of a 20k-vertex grid: the correction is far
  // smaller than the raw positions (12 bytes a vertex).
  Mesh base;
  for (int j = 0; j < 141; ++j)
    for (int i = 0; i < 141; ++i) base.positions.push_back({i * 0.01f, j * 0.01f, 0.5f});
  for (int j = 0; j < 140; ++j)
    for (int i = 0; i < 140; ++i) {
      Index a = j * 141 + i;
      base.triangles.push_back({a, a + 1, a + 142});
      base.triangles.push_back({a, a + 142, a + 141});
    }
  std::vector<mesh::Point> moved = base.positions;
  for (std::size_t v = 0; v < moved.size(); ++v) moved[v][2] += 1e-4f * static_cast<float>((v * 7919) % 13);
  Mesh result = base;
  result.positions = moved;
  auto bytes = encode_correction(base, mesh::mesh_sha256(base), mesh::mesh_sha256(result), {MoveAllVertices{moved}});
  EXPECT_LT(bytes.size(), base.positions.size() * 2);
  EXPECT_EQ(apply_correction(base, bytes), result);
}

// A 100 x 100 grid's middle 40 x 40 quads cut out and patched back with new vertices: the
// patch's corners are coded from the cache and the fresh-vertex rule, and it round-trips.
TEST(Correction, AddedPatchesRoundTripAndCostLittle) {
  auto grid = [](int n) {
    Mesh m;
    for (int j = 0; j <= n; ++j)
      for (int i = 0; i <= n; ++i) m.positions.push_back({i * 0.01f, j * 0.01f, 0.001f * float((i * j) % 7)});
    return m;
  };
  const int n = 100;
  auto id = [&](int i, int j) { return static_cast<Index>(j * (n + 1) + i); };
  auto inside = [](int i, int j) { return i >= 30 && i < 70 && j >= 30 && j < 70; };
  Mesh base = grid(n);
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (!inside(i, j)) {
        base.triangles.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        base.triangles.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      }
  EditMesh m(base);
  // New vertices replace the 39 x 39 interior grid points (added in first-use order).
  std::map<Index, Index> fresh;
  auto corner = [&](int i, int j) {
    bool interior = i > 30 && i < 70 && j > 30 && j < 70;
    if (!interior) return id(i, j);
    auto [it, added] = fresh.try_emplace(id(i, j), 0);
    if (added) it->second = m.add_vertex(base.positions[id(i, j)]);
    return it->second;
  };
  std::size_t added_triangles = 0;
  for (int j = 30; j < 70; ++j)
    for (int i = 30; i < 70; ++i) {
      Index a = corner(i, j), b = corner(i + 1, j), c = corner(i + 1, j + 1), d = corner(i, j + 1);
      m.add_triangle(a, b, c);
      m.add_triangle(a, c, d);
      added_triangles += 2;
    }
  Mesh result = m.compact();
  auto bytes = encode_correction(base, mesh::mesh_sha256(base), mesh::mesh_sha256(result), m.edits());
  EXPECT_EQ(mesh::mesh_sha256(apply_correction(base, bytes)), mesh::mesh_sha256(result));
  EXPECT_LT(bytes.size(), added_triangles / 2) << bytes.size();  // 1270 B when written; raw ids: 12 B a triangle
}

// Corners in an order no model predicts (a shuffled soup re-added) still round-trip.
TEST(Correction, UnpredictableCornersRoundTrip) {
  Mesh base = two_cubes_sharing_an_edge();
  EditMesh m(base);
  std::vector<Index> added;
  for (int k = 0; k < 40; ++k) added.push_back(m.add_vertex({float(k), float(k % 3), float(k % 5)}));
  for (int k = 0; k < 200; ++k) {
    Index a = added[(k * 7) % 40], b = static_cast<Index>((k * 5) % 14), c = added[(k * 13 + 1) % 40];
    if (a != c) m.add_triangle(a, b, c);
  }
  Mesh result = m.compact();
  auto bytes = encode_correction(base, mesh::mesh_sha256(base), mesh::mesh_sha256(result), m.edits());
  EXPECT_EQ(apply_correction(base, bytes), result);
}

}  // namespace
}  // namespace meshflow::protocol
