#include "mesh/mesh_io.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/measures.h"
#include "tests/support/manifest.h"
#include "tests/support/meshes.h"

namespace meshflow::mesh {
namespace {

using namespace meshflow::testing;

TEST(MeshReaders, EveryValidSharedMeshGivesItsManifestCounts) {
  auto rows = manifest();
  ASSERT_GT(rows.size(), 40u);
  int checked = 0;
  for (const auto& row : rows) {
    if (row.v == "-" || must_refuse(row.file)) continue;
    SCOPED_TRACE(row.file);
    ReadInfo info;
    Mesh mesh = read_mesh(shared_meshes() + "/" + row.file, &info);
    Measures m = compute_measures(mesh);
    EXPECT_EQ(std::to_string(m.vertices), row.v);
    EXPECT_EQ(std::to_string(info.faces_read), row.f);  // faces as stored, polygons once
    EXPECT_EQ(std::to_string(m.components), row.cc);
    EXPECT_EQ(std::to_string(m.boundary_loops), row.loops);
    if (row.notes.find("faces with >3 vertices") != std::string::npos) EXPECT_GT(info.polygons, 0u);
    else EXPECT_EQ(m.triangles, info.faces_read);
    ++checked;
  }
  EXPECT_GE(checked, 39);
}

TEST(MeshReaders, EveryBrokenSharedMeshIsRefusedNamingTheFileAndPlace) {
  int refused = 0;
  for (const auto& row : manifest()) {
    if (!must_refuse(row.file)) continue;
    SCOPED_TRACE(row.file);
    std::string path = shared_meshes() + "/" + row.file;
    try {
      read_mesh(path);
      ADD_FAILURE() << "accepted";
    } catch (const ParseError& e) {
      std::string what = e.what();
      EXPECT_NE(what.find(path), std::string::npos) << what;
      EXPECT_TRUE(e.where().line || e.where().byte_offset) << what;
      ++refused;
    }
  }
  EXPECT_GE(refused, 15);
}

Mesh sample_mesh() {
  Mesh m = cube();
  m.positions.push_back({0.1f, -3.25e-7f, 12345.678f});  // an unreferenced vertex
  m.positions[2][1] = 1.0f / 3.0f;                       // a float that prints long
  return m;
}

TEST(MeshWriters, RoundTripPreservesTheMeshInEveryIndexedFormat) {
  TempDir dir;
  Mesh original = sample_mesh();
  for (std::string name : {"m.ply", "m.off", "m.obj", "m.ply.gz", "m.off.zst", "m.obj.gz"}) {
    SCOPED_TRACE(name);
    write_mesh(original, dir.file(name));
    Mesh back = read_mesh(dir.file(name));
    EXPECT_EQ(back, original);
  }
}

TEST(MeshWriters, StlRoundTripKeepsTheTrianglesUpToWelding) {
  TempDir dir;
  Mesh original = cube();
  write_mesh(original, dir.file("m.stl"));
  ReadInfo info;
  Mesh back = read_mesh(dir.file("m.stl"), &info);
  EXPECT_TRUE(info.is_binary);
  ASSERT_EQ(back.triangles.size(), original.triangles.size());
  EXPECT_EQ(back.positions.size(), 8u);
  for (std::size_t t = 0; t < original.triangles.size(); ++t)
    for (int k = 0; k < 3; ++k)
      EXPECT_EQ(back.positions[back.triangles[t][k]], original.positions[original.triangles[t][k]]);
}

// Every valid shared mesh through every format: PLY, OFF and OBJ give it back exactly (ids,
// float32 bits, unreferenced vertices); STL, which has no shared vertices, gives back the same
// triangles, corner by corner, once welded.
TEST(MeshWriters, EverySharedMeshSurvivesEveryFormat) {
  TempDir dir;
  for (const std::string& file : valid_shared_meshes()) {
    SCOPED_TRACE(file);
    Mesh original = read_mesh(shared_meshes() + "/" + file);
    for (std::string name : {"m.ply", "m.off", "m.obj"}) {
      write_mesh(original, dir.file(name));
      EXPECT_TRUE(read_mesh(dir.file(name)) == original) << name;
    }
    write_mesh(original, dir.file("m.stl"));
    Mesh back = read_mesh(dir.file("m.stl"));
    ASSERT_EQ(back.triangles.size(), original.triangles.size());
    std::size_t differing = 0;
    for (std::size_t t = 0; t < original.triangles.size(); ++t)
      for (int k = 0; k < 3; ++k)
        differing += back.positions[back.triangles[t][k]] != original.positions[original.triangles[t][k]];
    EXPECT_EQ(differing, 0u);
  }
}

TEST(MeshReaders, OneMeshReadsTheSameInEveryEncoding) {
  auto canonical = [](const std::string& file) { return canonical_ply_bytes(read_mesh(shared_meshes() + "/" + file)); };
  // (Spider_ascii.stl prints 6 decimals, so it is not bit-identical to Spider_binary.stl.)
  EXPECT_EQ(canonical("malformed/elephant_ascii.ply"), canonical("malformed/elephant_le.ply"));
  EXPECT_EQ(canonical("malformed/elephant_be.ply"), canonical("malformed/elephant_le.ply"));
  EXPECT_EQ(canonical("malformed/elephant_ascii.stl"), canonical("malformed/elephant_binary.stl"));
  EXPECT_EQ(canonical("formats/icosahedron_ascii.stl"), canonical("formats/icosahedron_binary.stl"));
  // The OBJ with relative indices reorders the faces, but holds the same triangles.
  Mesh obj = read_mesh(shared_meshes() + "/malformed/elephant_negidx.obj");
  Mesh ply = read_mesh(shared_meshes() + "/malformed/elephant_le.ply");
  EXPECT_EQ(obj.positions, ply.positions);
  std::sort(obj.triangles.begin(), obj.triangles.end());
  std::sort(ply.triangles.begin(), ply.triangles.end());
  EXPECT_EQ(obj.triangles, ply.triangles);
}

TEST(MeshWriters, PlyOutputIsTheCanonicalSerialization) {
  TempDir dir;
  Mesh m = sample_mesh();
  write_mesh(m, dir.file("c.ply"));
  std::ifstream in(dir.file("c.ply"), std::ios::binary);
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  auto expected = canonical_ply_bytes(m);
  EXPECT_EQ(bytes, std::string(expected.begin(), expected.end()));
}

TEST(MeshWriters, UnknownExtensionIsRefused) {
  TempDir dir;
  EXPECT_THROW(write_mesh(cube(), dir.file("m.xyz")), InvalidInput);
}

TEST(MeshReaders, FormatIsDetectedFromContentNotExtension) {
  TempDir dir;
  write_mesh(cube(), dir.file("a.off"));
  std::filesystem::rename(dir.file("a.off"), dir.file("a.ply"));
  ReadInfo info;
  EXPECT_EQ(read_mesh(dir.file("a.ply"), &info), cube());
  EXPECT_EQ(info.format, Format::Off);
  write_mesh(cube(), dir.file("b.obj.zst"));
  std::filesystem::rename(dir.file("b.obj.zst"), dir.file("b.mesh"));
  EXPECT_EQ(read_mesh(dir.file("b.mesh"), &info), cube());
  EXPECT_EQ(info.format, Format::Obj);
  EXPECT_EQ(info.compression, Compression::Zstd);
}

// Reads text as a mesh and returns the error message ("" when it was accepted).
std::string error_of(const std::string& text, const std::string& name) {
  std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  try {
    read_mesh_from_memory(bytes, name);
  } catch (const ParseError& e) {
    return e.what();
  }
  return "";
}

TEST(MeshReaders, BadInputGetsOneClearLine) {
  EXPECT_EQ(error_of("", "e.off"), "e.off: byte 0: empty file: expected a PLY, OFF, OBJ or STL mesh");
  EXPECT_EQ(error_of("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n", "two.off"),
            "two.off:6: face 0 has 2 vertices; expected at least 3");
  EXPECT_EQ(error_of("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n", "range.off"),
            "range.off:6: face 0: vertex index 3 out of range (3 vertices)");
  EXPECT_EQ(error_of("OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "nan.off"),
            "nan.off:4: vertex 1 has a coordinate that is not a finite float");
  EXPECT_EQ(error_of("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "short.off"),
            "short.off:6: unexpected end of file: expected 2 faces, found 1");
  EXPECT_EQ(error_of("v 0 0 0\nv 1 0 0\nf 1 2 3\n", "fwd.obj"),
            "fwd.obj:3: face: vertex index 3 out of range (2 vertices defined so far; indices are 1-based)");
  EXPECT_EQ(error_of("v 0 0 1e999\n", "inf.obj"), "inf.obj:1: vertex 1 has a coordinate that is not a finite float");
  EXPECT_NE(error_of("ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nend_header\n0\n", "noy.ply")
                .find("no scalar property 'y'"),
            std::string::npos);
  EXPECT_NE(error_of("ply\nformat binary 1.0\nend_header\n", "g.ply").find("g.ply:2: unknown PLY format"),
            std::string::npos);
  EXPECT_NE(error_of("hello world\n", "junk.txt").find("junk.txt: byte 0: unrecognised content"),
            std::string::npos);
}

TEST(MeshReaders, BinaryErrorsNameTheByteOffset) {
  std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  std::string body(36, '\0');
  std::string face = std::string(1, '\3') + std::string(4, '\0') + std::string(4, '\0');  // cut short
  std::string message = error_of(header + body + face, "cut.ply");
  EXPECT_NE(message.find("cut.ply: byte " + std::to_string(header.size() + 36 + 1) +
                         ": unexpected end of file in element face 0 of 1: expected 12 more bytes"),
            std::string::npos)
      << message;
}

// A list count is the file's word: 4 billion doubles announced in a 100-byte file are an error
// naming the byte, not 32 GB asked of the allocator.
TEST(MeshReaders, AHugeListCountInAShortFileIsAnErrorNotAnAllocation) {
  std::string header =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 1\nproperty list uchar int vertex_indices\nproperty list uint double weights\n"
      "end_header\n";
  std::string indices = std::string(1, '\3') + std::string(4, '\0') + std::string("\1\0\0\0", 4) + std::string("\2\0\0\0", 4);
  std::string face = indices + std::string(4, '\xff') + std::string(16, '\0');
  std::string message = error_of(header + std::string(36, '\0') + face, "huge.ply");
  EXPECT_NE(message.find("huge.ply: byte " + std::to_string(header.size() + 36 + 13 + 4) +
                         ": unexpected end of file in element face 0 of 1: expected " +
                         std::to_string(std::uint64_t{0xFFFFFFFF} * 8) + " more bytes"),
            std::string::npos)
      << message;
}

TEST(MeshReaders, PlyWithExtraPropertiesBigEndianAndPolygons) {
  // Big endian, a double coordinate, an extra uchar per vertex, a quad with a colour list.
  std::string text =
      "ply\nformat binary_big_endian 1.0\ncomment extra props\nelement vertex 4\n"
      "property double x\nproperty float y\nproperty float z\nproperty uchar flag\n"
      "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar uchar rgb\nend_header\n";
  auto be32 = [](std::uint32_t v) {
    return std::string{char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
  };
  auto bef = [&](float f) { return be32(std::bit_cast<std::uint32_t>(f)); };
  auto bed = [](double d) {
    std::uint64_t v = std::bit_cast<std::uint64_t>(d);
    std::string s;
    for (int i = 7; i >= 0; --i) s += char(v >> (8 * i));
    return s;
  };
  float xs[4] = {0, 1, 1, 0}, ys[4] = {0, 0, 1, 1};
  for (int i = 0; i < 4; ++i) text += bed(xs[i]) + bef(ys[i]) + bef(2.5f) + std::string(1, '\7');
  text += std::string(1, '\4') + be32(0) + be32(1) + be32(2) + be32(3) + std::string(1, '\3') + "abc";
  std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(text.data()), text.size());
  ReadInfo info;
  Mesh m = read_mesh_from_memory(bytes, "be.ply", &info);
  ASSERT_EQ(m.positions.size(), 4u);
  EXPECT_EQ(m.positions[2], (Point{1, 1, 2.5f}));
  ASSERT_EQ(m.triangles.size(), 2u);
  EXPECT_EQ(m.triangles[1], (Triangle{0, 2, 3}));
  EXPECT_EQ(info.polygons, 1u);
}

TEST(MeshReaders, StreamingHandsOutVerticesWithoutFacesWhenAsked) {
  struct VertexCounter : MeshSink {
    std::size_t vertices_seen = 0, triangles_seen = 0;
    void vertices(std::span<const Point> b) override { vertices_seen += b.size(); }
    void triangles(std::span<const Triangle> b) override { triangles_seen += b.size(); }
    bool wants_triangles() const override { return false; }
  } counter;
  stream_mesh(shared_meshes() + "/large/terrain_fuji_512.ply", counter);
  EXPECT_EQ(counter.vertices_seen, 262144u);
  EXPECT_EQ(counter.triangles_seen, 0u);
}

}  // namespace
}  // namespace meshflow::mesh
