#include "protocol/correction.h"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace meshflow::protocol
