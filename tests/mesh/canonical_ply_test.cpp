#include "mesh/canonical_ply.h"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <sstream>

namespace meshflow::mesh {
namespace {

Mesh one_triangle() {
  Mesh mesh;
  mesh.positions = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  mesh.triangles = {{0, 1, 2}};
  return mesh;
}

TEST(CanonicalPly, HeaderIsExactlyTheDesignHeader) {
  EXPECT_EQ(canonical_ply_header(3, 1),
            "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nelement face 1\n"
            "property list uchar int vertex_indices\nend_header\n");
}

TEST(CanonicalPly, BytesHaveThePredictedSizeAndLayout) {
  Mesh mesh = one_triangle();
  auto bytes = canonical_ply_bytes(mesh);
  std::size_t header = canonical_ply_header(3, 1).size();
  ASSERT_EQ(bytes.size(), canonical_ply_size(3, 1));
  ASSERT_EQ(bytes.size(), header + 3 * 12 + 13);
  EXPECT_EQ(bytes[header + 36], 3);  // the list count of the face
  float x1;
  std::memcpy(&x1, &bytes[header + 12], 4);
  EXPECT_EQ(x1, 1.0f);
}

TEST(CanonicalPly, StreamAndMemoryAndHashAgree) {
  Mesh mesh = one_triangle();
  std::ostringstream out;
  write_canonical_ply(mesh, out);
  auto bytes = canonical_ply_bytes(mesh);
  EXPECT_EQ(out.str(), std::string(bytes.begin(), bytes.end()));
  EXPECT_EQ(mesh_sha256(mesh), sha256_hex(bytes.data(), bytes.size()));
}

TEST(Sha256, MatchesTheKnownDigestOfAbc) {
  EXPECT_EQ(sha256_hex("abc", 3),
            "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(BoundingBox, DiagonalOfUnitSquare) {
  EXPECT_DOUBLE_EQ(bounding_box(one_triangle()).diagonal(), std::sqrt(2.0));
}

}  // namespace
}  // namespace meshflow::mesh
