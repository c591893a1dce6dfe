// Bad input, reader by reader (mesh/readers.h): empty, truncated, trailing bytes, garbage
// headers, wrong counts, a face with 2 vertices, indices out of range, NaN/inf coordinates,
// absurd declared sizes. Each must give one ParseError naming the file and the line (text) or
// byte offset (binary), and what was expected.
#include "mesh/readers.h"

#include <gtest/gtest.h>

#include <bit>
#include <cmath>
#include <cstring>
#include <fstream>
#include <limits>
#include <string>

#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "tests/support/meshes.h"

namespace meshflow::mesh {
namespace {

struct Refusal {
  std::string message;
  std::optional<std::uint64_t> line, byte;
};

// Reads bytes as a mesh named `name`; the refusal, or an empty message when it was accepted.
Refusal refusal_of(const std::string& bytes, const std::string& name) {
  std::span<const std::uint8_t> span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  try {
    read_mesh_from_memory(span, name);
  } catch (const ParseError& e) {
    return {e.what(), e.where().line, e.where().byte_offset};
  }
  return {};
}

// Expects a refusal at `line` whose message starts with the file name and holds `phrase`.
void expect_line(const std::string& bytes, const std::string& name, std::uint64_t line, const std::string& phrase) {
  SCOPED_TRACE(name);
  Refusal r = refusal_of(bytes, name);
  ASSERT_FALSE(r.message.empty()) << "accepted";
  EXPECT_EQ(r.message.rfind(name + ":" + std::to_string(line) + ": ", 0), 0u) << r.message;
  EXPECT_EQ(r.line, line) << r.message;
  EXPECT_NE(r.message.find(phrase), std::string::npos) << r.message;
}

void expect_byte(const std::string& bytes, const std::string& name, std::uint64_t byte, const std::string& phrase) {
  SCOPED_TRACE(name);
  Refusal r = refusal_of(bytes, name);
  ASSERT_FALSE(r.message.empty()) << "accepted";
  EXPECT_EQ(r.message.rfind(name + ": byte " + std::to_string(byte) + ": ", 0), 0u) << r.message;
  EXPECT_EQ(r.byte, byte) << r.message;
  EXPECT_NE(r.message.find(phrase), std::string::npos) << r.message;
}

// Little- or big-endian bytes of a value.
template <typename T>
std::string bytes_of(T value, bool big_endian = false) {
  std::string s(sizeof(T), '\0');
  std::memcpy(s.data(), &value, sizeof(T));
  if (big_endian) std::reverse(s.begin(), s.end());
  return s;
}

const std::string kAsciiPly =
    "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 1\nproperty list uchar int vertex_indices\nend_header\n";  // 9 lines

std::string binary_ply_header(bool big_endian) {
  return std::string("ply\nformat ") + (big_endian ? "binary_big_endian" : "binary_little_endian") +
         " 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 1\nproperty list uchar int vertex_indices\nend_header\n";
}

std::string binary_vertices(bool big_endian, float bad = 0) {
  std::string s;
  float xyz[9] = {0, 0, 0, 1, 0, 0, 0, 1, bad};
  for (float f : xyz) s += bytes_of(f, big_endian);
  return s;
}

std::string binary_face(bool big_endian, std::vector<std::int32_t> ids) {
  std::string s(1, static_cast<char>(ids.size()));
  for (auto i : ids) s += bytes_of(i, big_endian);
  return s;
}

TEST(PlyReader, AsciiBadInputNamesTheLine) {
  const std::string v = "0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_EQ(refusal_of(kAsciiPly + v + "3 0 1 2\n", "ok.ply").message, "");
  expect_line(kAsciiPly + "0 0 0\n1 0 0\n", "cut.ply", 11, "unexpected end of file in element vertex 2 of 3");
  expect_line(kAsciiPly + v + "2 0 1\n", "two.ply", 13, "face 0 has 2 vertices; expected at least 3");
  expect_line(kAsciiPly + v + "3 0 1 3\n", "range.ply", 13, "vertex index 3 out of range (3 vertices)");
  expect_line(kAsciiPly + v + "3 0 -1 2\n", "negative.ply", 13, "vertex index -1 out of range");
  expect_line(kAsciiPly + "0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "nan.ply", 11, "not a finite float");
  expect_line(kAsciiPly + "0 0 0\n1 inf 0\n0 1 0\n3 0 1 2\n", "inf.ply", 11, "not a finite float");
  expect_line(kAsciiPly + "0 0 0\n1 0 0\n0 1 1e39\n3 0 1 2\n", "big.ply", 12, "not a finite float");
  expect_line(kAsciiPly + "0 0 0\n1 x 0\n0 1 0\n3 0 1 2\n", "garbage.ply", 11,
              "property 'y' expects a number (float), found 'x'");
  expect_line(kAsciiPly + v + "300 0 1 2\n", "count.ply", 13, "expected a list count (uchar), found '300'");
  expect_line(kAsciiPly + v + "3 0 1 2\n3 0 1 2\n", "trailing.ply", 14, "unexpected data after the last element");
}

TEST(PlyReader, GarbageHeadersAreRefused) {
  expect_line("ply\nformat ascii 1.0\nelement vertex 3\nproperty floaty x\nend_header\n", "type.ply", 4,
              "unknown property type 'floaty'");
  expect_line("ply\nformat ascii 1.0\nelement vertex 3\n", "open.ply", 3, "no end_header");
  expect_line("ply\nformat ascii 2.0\nelement vertex 0\nend_header\n", "version.ply", 2,
              "unsupported PLY version '2.0'");
  expect_line("ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", "count.ply", 3,
              "expected 'element NAME COUNT' with a count >= 0");
  expect_line("ply\nformat binary 1.0\nend_header\n", "format.ply", 2, "unknown PLY format");
  expect_line("ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\nend_header\n1 0\n",
              "list.ply", 3, "no scalar property 'x'");
  expect_line("ply\nformat ascii 1.0\nelement face 0\nproperty list uchar int vertex_indices\nend_header\n",
              "novertex.ply", 1, "no 'vertex' element");
  expect_line("ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
              "element face 0\nproperty float area\nend_header\n",
              "noindices.ply", 7, "element face has no integer list property 'vertex_indices'");
  expect_line("ply\n", "header.ply", 1, "no end_header");
}

TEST(PlyReader, BinaryBadInputNamesTheByte) {
  for (bool big : {false, true}) {
    std::string h = binary_ply_header(big), tag = big ? "be" : "le";
    std::uint64_t faces_at = h.size() + 36;
    EXPECT_EQ(refusal_of(h + binary_vertices(big) + binary_face(big, {0, 1, 2}), "ok.ply").message, "");
    expect_byte(h + binary_vertices(big).substr(0, 20), "cut_" + tag + ".ply", h.size() + 12,
                "unexpected end of file in element vertex 1 of 3: expected 12 more bytes");
    expect_byte(h + binary_vertices(big) + binary_face(big, {0, 1, 2}).substr(0, 9), "cutface_" + tag + ".ply",
                faces_at + 1, "unexpected end of file in element face 0 of 1: expected 12 more bytes");
    // A face's errors point at the start of its record.
    expect_byte(h + binary_vertices(big) + binary_face(big, {0, 1}), "two_" + tag + ".ply", faces_at,
                "face 0 has 2 vertices; expected at least 3");
    expect_byte(h + binary_vertices(big) + binary_face(big, {0, 1, 7}), "range_" + tag + ".ply", faces_at,
                "vertex index 7 out of range (3 vertices)");
    expect_byte(h + binary_vertices(big, std::numeric_limits<float>::quiet_NaN()) + binary_face(big, {0, 1, 2}),
                "nan_" + tag + ".ply", h.size() + 24, "vertex 2 has a coordinate that is not a finite float");
    expect_byte(h + binary_vertices(big, std::numeric_limits<float>::infinity()) + binary_face(big, {0, 1, 2}),
                "inf_" + tag + ".ply", h.size() + 24, "not a finite float");
    expect_byte(h + binary_vertices(big) + binary_face(big, {0, 1, 2}) + "xx", "trailing_" + tag + ".ply",
                faces_at + 13, "unexpected data after the last element (2+ trailing bytes)");
  }
}

TEST(PlyReader, AbsurdDeclaredCountsAreNotAllocated) {
  std::string h =
      "ply\nformat binary_little_endian 1.0\nelement vertex 4000000000\nproperty float x\nproperty float y\n"
      "property float z\nelement face 4000000000\nproperty list uchar int vertex_indices\nend_header\n";
  expect_byte(h + std::string(40, '\0'), "huge.ply", h.size() + 36,
              "unexpected end of file in element vertex 3 of 4000000000");
}

TEST(OffReader, BadInputNamesTheLine) {
  const std::string head = "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n";
  EXPECT_EQ(refusal_of(head + "3 0 1 2\n", "ok.off").message, "");
  expect_line("\n\n  \n", "blank.off", 3, "empty file: expected an OFF header");
  expect_line("OFF\nthree 1 0\n", "counts.off", 2, "expected 'VERTICES FACES EDGES' counts");
  expect_line("OFF\n3 1 0\n0 0 0\n1 0\n", "cut.off", 4, "vertex 1: expected 3 coordinates");
  expect_line(head + "2 0 1\n", "two.off", 6, "face 0 has 2 vertices; expected at least 3");
  expect_line(head + "3 0 1\n", "short.off", 6, "face 0: expected 3 vertex indices");
  expect_line(head + "3 0 -1 2\n", "negative.off", 6, "vertex index -1 out of range (3 vertices)");
  expect_line(head + "3 0 1 3\n", "range.off", 6, "vertex index 3 out of range (3 vertices)");
  expect_line("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 inf\n3 0 1 2\n", "inf.off", 5, "not a finite float");
  expect_line("OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n", "nan.off", 4, "not a finite float");
  expect_line(head + "3 0 1 2\n3 0 1 2\n", "trailing.off", 7, "unexpected data after the 1 faces");
  expect_line("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "fewer.off", 6, "expected 2 faces, found 1");
  expect_line("OFF\n4000000000 4000000000 0\n0 0 0\n", "huge.off", 3, "expected 4000000000 vertices, found 1");
}

TEST(ObjReader, BadInputNamesTheLine) {
  const std::string v = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  EXPECT_EQ(refusal_of(v + "f 1 2 3\nf -3 -2 -1\n", "ok.obj").message, "");
  expect_line("# nothing\n\n", "comments.obj", 2, "empty file: no OBJ statements");
  expect_line(v + "f 1 2\n", "two.obj", 4, "face has 2 vertices; expected at least 3");
  expect_line(v + "f 0 1 2\n", "zero.obj", 4, "vertex index 0 out of range (3 vertices defined so far");
  expect_line(v + "f -1 -2 -4\n", "negative.obj", 4, "vertex index -4 out of range");
  expect_line(v + "f 1 2 4\n", "forward.obj", 4, "vertex index 4 out of range");
  expect_line(v + "f 1 2 x\n", "garbage.obj", 4, "face: expected a vertex index, found 'x'");
  expect_line("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n", "nan.obj", 2, "vertex 2 has a coordinate that is not a finite float");
  expect_line("v 0 0\n", "short.obj", 1, "vertex 1: expected 3 coordinates");
  expect_line(v + "f 1 2 3\nv 0 0", "cut.obj", 5, "vertex 4: expected 3 coordinates");
  expect_line("v 0 0 0\nbogus 1 2\n", "unknown.obj", 2, "unknown OBJ statement 'bogus'");
}

const std::string kAsciiStl =
    "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
    "endsolid t\n";

std::string replace(std::string s, const std::string& from, const std::string& to) {
  return s.replace(s.find(from), from.size(), to);
}

TEST(StlReader, AsciiBadInputNamesTheLine) {
  EXPECT_EQ(refusal_of(kAsciiStl, "ok.stl").message, "");
  expect_line(kAsciiStl.substr(0, 60), "cut.stl", 5, "facet 0: expected 3 coordinates after 'vertex', found ''");
  expect_line(kAsciiStl.substr(0, 64), "cutline.stl", 5, "unexpected end of file inside a solid");
  expect_line(replace(kAsciiStl, "vertex 1 0 0", "vertex nan 0 0"), "nan.stl", 5, "facet 0 has a vertex coordinate that is not finite");
  expect_line(replace(kAsciiStl, "vertex 1 0 0", "vertex 1 zero 0"), "garbage.stl", 5, "found 'zero'");
  expect_line(replace(kAsciiStl, "vertex 0 1 0\n", ""), "two.stl", 6, "expected 3 vertices before 'endloop'");
  expect_line(kAsciiStl + "garbage\n", "trailing.stl", 10, "expected 'solid'");
  expect_line("solid t\nfacet normal 0 0 1\nloop\n", "keyword.stl", 3, "expected 'outer loop' or 'endfacet'");
}

std::string binary_stl(std::uint32_t declared, int records, float bad = 0) {
  std::string s = "binary stl" + std::string(70, '\0') + bytes_of(declared);
  float r[12] = {0, 0, 1, 0, 0, 0, 1, 0, 0, 0, 1, bad};
  for (int i = 0; i < records; ++i) {
    for (float f : r) s += bytes_of(f);
    s += std::string(2, '\0');
  }
  return s;
}

TEST(StlReader, BinaryBadInputNamesTheByte) {
  EXPECT_EQ(refusal_of(binary_stl(1, 1), "ok.stl").message, "");
  expect_byte(binary_stl(2, 1) + std::string(20, '\0'), "count.stl", 80,
              "binary STL header says 2 triangles (184 bytes) but the file has 154 bytes");
  expect_byte(binary_stl(1, 1) + std::string(7, '\0'), "trailing.stl", 80, "header says 1 triangles (134 bytes) but the file has 141");
  expect_byte(binary_stl(0xFFFFFFFFu, 1), "huge.stl", 80, "header says 4294967295 triangles");
  expect_byte(binary_stl(1, 1, std::numeric_limits<float>::infinity()), "inf.stl", 84,
              "facet 0 has a vertex coordinate that is not finite");
  expect_byte(binary_stl(1, 1).substr(0, 50), "short.stl", 0, "expected 84 more bytes, found 50");
}

// The bytes of `mesh` written by write_mesh to a file named `name` (.gz or .zst compresses).
std::string written(const Mesh& mesh, const std::string& name) {
  testing::TempDir dir;
  write_mesh(mesh, dir.file(name));
  std::ifstream in(dir.file(name), std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

TEST(CompressedInput, TruncatedOrCorruptStreamsAreRefused) {
  std::string gz = written(testing::cube(), "c.off.gz"), zs = written(testing::cube(), "c.off.zst");
  EXPECT_EQ(refusal_of(gz, "ok.off.gz").message, "");
  EXPECT_EQ(refusal_of(zs, "ok.off.zst").message, "");
  for (auto [bytes, name, phrase] : {std::tuple{gz.substr(0, gz.size() - 4), "cut.off.gz", "truncated gzip stream"},
                                     std::tuple{zs.substr(0, zs.size() - 4), "cut.off.zst", "truncated zstd stream"}}) {
    Refusal r = refusal_of(bytes, name);
    EXPECT_NE(r.message.find(std::string(name) + ": byte "), std::string::npos) << r.message;
    EXPECT_NE(r.message.find(phrase), std::string::npos) << r.message;
    EXPECT_NE(r.message.find("expected more compressed data"), std::string::npos) << r.message;
  }
  std::string corrupt = gz;
  corrupt[12] = static_cast<char>(0xff);
  corrupt[13] = static_cast<char>(0xff);
  Refusal r = refusal_of(corrupt, "bad.off.gz");
  EXPECT_NE(r.message.find("bad.off.gz"), std::string::npos) << r.message;
  EXPECT_FALSE(r.message.empty());
}

Mesh accepted(const std::string& bytes, const std::string& name, ReadInfo* info = nullptr) {
  std::span<const std::uint8_t> span(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
  return read_mesh_from_memory(span, name, info);
}

TEST(OffReader, VariantsSkipTheirExtras) {
  const std::vector<Point> xyz = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
  const std::vector<Triangle> tris = {{0, 1, 2}, {2, 1, 3}};
  struct Case { const char* name; std::string text; };
  const Case cases[] = {
      {"plain", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2\n3 2 1 3\n"},
      {"counts inline, comments", "# c\nOFF 4 2 0 # counts here\n0 0 0\n1 0 0\n0 1 0\n1 1 0\n3 0 1 2 # x\n3 2 1 3\n"},
      {"COFF", "COFF\n4 2 0\n0 0 0 255 0 0 255\n1 0 0 0 255 0 255\n0 1 0 0 0 255 255\n1 1 0 9 9 9 255\n"
               "3 0 1 2 1 0 0\n3 2 1 3 0.5 0.5 0.5 1\n"},
      {"NOFF", "NOFF\n4 2 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n1 1 0 0 0 1\n3 0 1 2\n3 2 1 3\n"},
      {"STCNOFF", "STCNOFF\n4 2 0\n0 0 0 0 0 1 1 1 1 1 0 0\n1 0 0 0 0 1 1 1 1 1 1 0\n0 1 0 0 0 1 1 1 1 1 0 1\n"
                  "1 1 0 0 0 1 1 1 1 1 1 1\n3 0 1 2\n3 2 1 3\n"},
      {"4OFF", "4OFF\n4 2 0\n0 0 0 2\n2 0 0 2\n0 4 0 4\n0.5 0.5 0 0.5\n3 0 1 2\n3 2 1 3\n"},
      {"quad", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    ReadInfo info;
    Mesh m = accepted(c.text, "v.off", &info);
    if (std::string(c.name) == "quad") {
      EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {0, 2, 3}}));  // fan from the first corner
      EXPECT_EQ(info.polygons, 1u);
      continue;
    }
    EXPECT_EQ(m.positions, xyz);
    EXPECT_EQ(m.triangles, tris);
  }
}

TEST(ObjReader, TokensGroupsAndRelativeIndices) {
  std::string text =
      "# exported\nmtllib a.mtl\no thing\ng part\ns 1\nusemtl red\n"
      "v 0 0 0\nv 1 0 0 1.0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvn 0 0 1\n"
      "f 1/1/1 2/2/1 3//1\nf -2/-1 -3/-2 -1\nf 1 2 4 3\nl 1 2\n";
  ReadInfo info;
  Mesh m = accepted(text, "t.obj", &info);
  EXPECT_EQ(m.positions.size(), 4u);
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {2, 1, 3}, {0, 1, 3}, {0, 3, 2}}));
  EXPECT_EQ(info.faces_read, 3u);
  EXPECT_EQ(info.polygons, 1u);
}

TEST(PlyReader, TristripsExpandWithAlternatingWindingAndRestarts) {
  std::string text =
      "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\nproperty float z\n"
      "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"
      "0 0 0\n1 0 0\n0 1 0\n1 1 0\n0 2 0\n1 2 0\n"
      "9 0 1 2 3 -1 2 3 4 5\n";
  ReadInfo info;
  Mesh m = accepted(text, "strip.ply", &info);
  // Strip 0 1 2 3: (0,1,2), (2,1,3); after the restart 2 3 4 5: (2,3,4), (4,3,5).
  EXPECT_EQ(m.triangles, (std::vector<Triangle>{{0, 1, 2}, {2, 1, 3}, {2, 3, 4}, {4, 3, 5}}));
}

TEST(Readers, EmptyAndUnrecognisedInput) {
  expect_byte("", "empty.ply", 0, "empty file: expected a PLY, OFF, OBJ or STL mesh");
  expect_byte("hello world\n", "junk.txt", 0, "unrecognised content: expected a PLY, OFF, OBJ or STL mesh");
  expect_byte(written(Mesh{}, "e.obj.gz").substr(0, 10), "empty.obj.gz", 0, "truncated gzip stream");
}

}  // namespace
}  // namespace meshflow::mesh
