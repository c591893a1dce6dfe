#include "mesh/canonical_copy.h"

#include <gtest/gtest.h>
#include <malloc.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/generate.h"
#include "mesh/mesh_io.h"
#include "tests/support/manifest.h"
#include "tests/support/meshes.h"

namespace meshflow::mesh {
namespace {

using namespace meshflow::testing;
namespace fs = std::filesystem;

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  std::stringstream text;
  text << in.rdbuf();
  return text.str();
}

std::vector<std::string> files_in(const TempDir& dir) {
  std::vector<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir.path)) names.push_back(entry.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The copy of `in` to `out_name` against write_mesh(read_mesh(in)) to "ref-" + out_name:
// the same bytes, hash, counts and box, and no scratch file left.
void expect_same_as_write_mesh(const std::string& in, const TempDir& dir, const std::string& out_name,
                               const CanonicalCopyParams& params = {}) {
  SCOPED_TRACE(in + " -> " + out_name);
  Mesh mesh = read_mesh(in);
  write_mesh(mesh, dir.file("ref-" + out_name));
  CanonicalCopy copy = copy_canonical_ply(in, dir.file(out_name), params);
  EXPECT_TRUE(slurp(dir.file(out_name)) == slurp(dir.file("ref-" + out_name))) << "bytes differ";
  EXPECT_EQ(copy.sha256, mesh_sha256(mesh));
  EXPECT_EQ(copy.vertices, mesh.num_vertices());
  EXPECT_EQ(copy.triangles, mesh.num_triangles());
  EXPECT_EQ(copy.canonical_bytes, canonical_ply_size(mesh.num_vertices(), mesh.num_triangles()));
  Box box = bounding_box(mesh);
  EXPECT_EQ(copy.box.min, box.min);
  EXPECT_EQ(copy.box.max, box.max);
  EXPECT_EQ(copy.diagonal, box.diagonal());
  EXPECT_FALSE(fs::exists(dir.file(out_name + ".vertices.tmp")));
  EXPECT_FALSE(fs::exists(dir.file(out_name + ".triangles.tmp")));
  EXPECT_FALSE(fs::exists(dir.file(out_name + ".tmp")));
}

// PLY (ascii, binary LE and BE, extra properties, polygons, tristrips), OFF variants, OBJ
// (vt/vn, negative indices, quads), STL ascii (several solids) and binary (welded).
TEST(CanonicalCopy, EverySharedMeshGivesTheBytesAndHashOfWriteMeshReadMesh) {
  TempDir dir;
  int checked = 0;
  for (const std::string& file : valid_shared_meshes()) {
    expect_same_as_write_mesh(shared_meshes() + "/" + file, dir, "out.ply");
    ++checked;
  }
  EXPECT_GE(checked, 39);
}

TEST(CanonicalCopy, CompressedInputAndOutputGiveTheBytesOfWriteMesh) {
  TempDir dir;
  Mesh dragon = read_mesh(shared_meshes() + "/real/dragon_100k.ply");
  Mesh kitten = read_mesh(shared_meshes() + "/real/kitten.off");
  write_mesh(dragon, dir.file("dragon.off.gz"));
  write_mesh(dragon, dir.file("dragon.obj.zst"));
  write_mesh(kitten, dir.file("kitten.ply.gz"));
  write_mesh(kitten, dir.file("kitten.stl.zst"));
  for (std::string in : {"dragon.off.gz", "dragon.obj.zst", "kitten.ply.gz", "kitten.stl.zst"})
    for (std::string out : {"c.ply", "c.ply.gz", "c.ply.zst"}) expect_same_as_write_mesh(dir.file(in), dir, out);
  // Small chunks: the compressors give the same bytes whatever the pieces they are handed.
  expect_same_as_write_mesh(dir.file("dragon.obj.zst"), dir, "small.ply.zst", {.buffer_bytes = 4096});
  expect_same_as_write_mesh(dir.file("dragon.off.gz"), dir, "small.ply.gz", {.buffer_bytes = 4096});
  // The hub's own case: a canonical .ply.zst copied again is the same file.
  CanonicalCopy again = copy_canonical_ply(dir.file("c.ply.zst"), dir.file("again.ply.zst"));
  EXPECT_TRUE(slurp(dir.file("again.ply.zst")) == slurp(dir.file("c.ply.zst")));
  EXPECT_EQ(again.sha256, mesh_sha256(read_mesh(dir.file("kitten.stl.zst"))));  // c.ply.zst's source
}

TEST(CanonicalCopy, ObjWithInterleavedVerticesFacesAndPolygons) {
  TempDir dir;
  std::ofstream(dir.file("in.obj")) << "# interleaved\nv 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 3\nvt 0 0\n"
                                       "v 0 1 0\nf -4 -2 -1\nv 2 0 0\nv 2 1 0\ng quad\nf 2/1 5/1 6/1 3/1\n"
                                       "v 3 0 0.5\nv 3 1 0.5\nv 3 2 0\nf 5//1 7//1 8//1 9//1 6//1\nv -1 -1 -1\n";
  expect_same_as_write_mesh(dir.file("in.obj"), dir, "out.ply");
  Mesh back = read_mesh(dir.file("out.ply"));
  EXPECT_EQ(back.num_vertices(), 10u);
  EXPECT_EQ(back.num_triangles(), 1u + 1u + 2u + 3u);
}

TEST(CanonicalCopy, PlyWithFacesBeforeVerticesAndExtraElements) {
  TempDir dir;
  std::ofstream(dir.file("in.ply")) << "ply\nformat ascii 1.0\ncomment faces first\nelement face 2\n"
                                       "property list uchar int vertex_indices\nproperty uchar red\n"
                                       "element vertex 5\nproperty double x\nproperty float nx\nproperty double y\n"
                                       "property double z\nelement edge 1\nproperty int a\nproperty int b\nend_header\n"
                                       "4 0 1 2 3 7\n3 3 2 4 9\n0 1 0 0\n1 0 0 0\n1 1 1 0\n0 1 1 0\n0.5 0 1.5 2\n0 1\n";
  expect_same_as_write_mesh(dir.file("in.ply"), dir, "out.ply");
  // No faces at all: the header still says so.
  std::ofstream(dir.file("points.ply")) << "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\n"
                                           "property float y\nproperty float z\nend_header\n0 0 0\n1 2 3\n";
  expect_same_as_write_mesh(dir.file("points.ply"), dir, "points-out.ply");
}

TEST(CanonicalCopy, StlIsWeldedAsReadMeshWeldsIt) {
  TempDir dir;
  std::ofstream(dir.file("in.stl"))
      << "solid a\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n"
         "endsolid a\nsolid b\nfacet normal 0 0 1\nouter loop\nvertex -0 0 0\nvertex 0 1 0\nvertex 0 1 1\nendloop\n"
         "endfacet\nendsolid b\n";
  expect_same_as_write_mesh(dir.file("in.stl"), dir, "out.ply");
  EXPECT_EQ(read_mesh(dir.file("out.ply")).num_vertices(), 4u);  // -0 welded onto 0
}

// Every broken shared file: the reader's own ParseError (file and line or byte), and neither
// output nor scratch file is left; an older output stays as it was.
TEST(CanonicalCopy, DamagedInputGivesTheReadersErrorAndLeavesNoFile) {
  int refused = 0;
  for (const auto& row : manifest()) {
    if (!must_refuse(row.file)) continue;
    SCOPED_TRACE(row.file);
    std::string path = shared_meshes() + "/" + row.file;
    std::string expected;
    try {
      read_mesh(path);
    } catch (const ParseError& e) {
      expected = e.what();
    }
    TempDir dir;
    try {
      copy_canonical_ply(path, dir.file("out.ply.zst"));
      ADD_FAILURE() << "accepted";
    } catch (const ParseError& e) {
      EXPECT_EQ(std::string(e.what()), expected);
      EXPECT_TRUE(e.where().line || e.where().byte_offset) << e.what();
      ++refused;
    }
    EXPECT_TRUE(files_in(dir).empty()) << ::testing::PrintToString(files_in(dir));
  }
  EXPECT_GE(refused, 15);

  TempDir dir;
  std::ofstream(dir.file("out.ply")) << "older";
  std::string truncated = shared_meshes() + "/malformed/elephant_truncated.ply";
  EXPECT_THROW(copy_canonical_ply(truncated, dir.file("out.ply")), ParseError);
  EXPECT_EQ(slurp(dir.file("out.ply")), "older");
  EXPECT_EQ(files_in(dir), std::vector<std::string>{"out.ply"});
}

TEST(CanonicalCopy, DamagedCompressedInputGivesTheReadersError) {
  TempDir dir;
  write_mesh(read_mesh(shared_meshes() + "/real/kitten.off"), dir.file("kitten.off.gz"));
  std::string bytes = slurp(dir.file("kitten.off.gz"));
  std::ofstream(dir.file("cut.off.gz"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::string expected;
  try {
    read_mesh(dir.file("cut.off.gz"));
  } catch (const ParseError& e) {
    expected = e.what();
  }
  ASSERT_NE(expected.find("cut.off.gz"), std::string::npos) << expected;
  try {
    copy_canonical_ply(dir.file("cut.off.gz"), dir.file("out.ply"));
    ADD_FAILURE() << "accepted";
  } catch (const ParseError& e) {
    EXPECT_EQ(std::string(e.what()), expected);
  }
  EXPECT_EQ(files_in(dir), (std::vector<std::string>{"cut.off.gz", "kitten.off.gz"}));
}

TEST(CanonicalCopy, RefusesAnOutputThatIsNotPlyBeforeReading) {
  TempDir dir;
  EXPECT_THROW(copy_canonical_ply(dir.file("missing.off"), dir.file("out.off")), InvalidInput);
  EXPECT_THROW(copy_canonical_ply(dir.file("missing.off"), dir.file("out.stl.zst")), InvalidInput);
  EXPECT_THROW(copy_canonical_ply(dir.file("missing.off"), dir.file("out.ply")), IoError);
  EXPECT_TRUE(files_in(dir).empty());
  EXPECT_TRUE(is_canonical_ply_path("a/b.PLY"));
  EXPECT_TRUE(is_canonical_ply_path("b.ply.zst"));
  EXPECT_TRUE(is_canonical_ply_path("b.ply.gz"));
  EXPECT_FALSE(is_canonical_ply_path("b.obj.gz"));
  EXPECT_FALSE(is_canonical_ply_path("b.zst"));
}

TEST(MeasureExtent, GivesTheVertexCountAndBoxOfReadMesh) {
  TempDir dir;
  write_mesh(read_mesh(shared_meshes() + "/real/igea_tristrips.ply"), dir.file("igea.ply.zst"));
  std::vector<std::string> files;
  for (const std::string& file : valid_shared_meshes()) files.push_back(shared_meshes() + "/" + file);
  files.push_back(dir.file("igea.ply.zst"));
  for (const std::string& path : files) {
    SCOPED_TRACE(path);
    Mesh mesh = read_mesh(path);
    MeshExtent extent = measure_extent(path);
    Box box = bounding_box(mesh);
    EXPECT_EQ(extent.vertices, mesh.num_vertices());
    EXPECT_EQ(extent.box.min, box.min);
    EXPECT_EQ(extent.box.max, box.max);
    EXPECT_EQ(extent.diagonal(), box.diagonal());
  }
  EXPECT_THROW(measure_extent(shared_meshes() + "/malformed/empty.ply"), ParseError);
}

// ---- memory ----

std::uint64_t status_kib(const char* field) {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line))
    if (line.rfind(field, 0) == 0) return std::strtoull(line.c_str() + std::strlen(field), nullptr, 10);
  return 0;
}

// How much `work` raises the peak resident size, in KiB, measured in a child process (so
// that nothing this test process did before counts): the heap's free memory is returned to
// the system, the peak is reset to the current size (/proc/self/clear_refs "5"), `work` runs,
// and the growth of VmHWM is reported.
template <typename Work>
std::int64_t peak_growth_kib(Work&& work) {
  int fds[2];
  if (pipe(fds) != 0) return -1;
  pid_t pid = fork();
  if (pid == 0) {
    close(fds[0]);
    std::int64_t growth = -1;
    try {
      malloc_trim(0);  // memory the parent freed but kept would otherwise serve `work` unseen
      std::ofstream("/proc/self/clear_refs") << "5";
      std::uint64_t before = status_kib("VmHWM:");
      work();
      growth = static_cast<std::int64_t>(status_kib("VmHWM:")) - static_cast<std::int64_t>(before);
    } catch (...) {
    }
    if (::write(fds[1], &growth, sizeof growth) != static_cast<ssize_t>(sizeof growth)) _exit(2);
    _exit(0);
  }
  close(fds[1]);
  std::int64_t growth = -1;
  if (::read(fds[0], &growth, sizeof growth) != static_cast<ssize_t>(sizeof growth)) growth = -1;
  close(fds[0]);
  waitpid(pid, nullptr, 0);
  return growth;
}

// A generated 2M-triangle terrain (about 1M vertices; 36 MB as a Mesh): the streaming copy's
// peak grows by its buffers only, far below the mesh, while read_mesh + write_mesh holds it.
TEST(CanonicalCopy, PeakMemoryOnA2MTriangleTerrainStaysFarBelowTheMesh) {
  TempDir dir;
  GenerateParams params;
  params.shape = Shape::Terrain;
  params.triangles = 2'000'000;
  GenerateResult terrain = generate_mesh(params, dir.file("terrain.ply"));
  const std::int64_t mesh_kib =
      static_cast<std::int64_t>((terrain.vertices * sizeof(Point) + terrain.triangles * sizeof(Triangle)) / 1024);
  std::int64_t copy_kib = peak_growth_kib([&] { copy_canonical_ply(dir.file("terrain.ply"), dir.file("copy.ply.zst")); });
  std::int64_t load_kib = peak_growth_kib([&] { write_mesh(read_mesh(dir.file("terrain.ply")), dir.file("load.ply.zst")); });
  std::int64_t measure_kib = peak_growth_kib([&] { measure_extent(dir.file("copy.ply.zst")); });
  RecordProperty("mesh_kib", std::to_string(mesh_kib));
  RecordProperty("copy_peak_growth_kib", std::to_string(copy_kib));
  RecordProperty("read_write_peak_growth_kib", std::to_string(load_kib));
  RecordProperty("measure_peak_growth_kib", std::to_string(measure_kib));
  std::printf("2M terrain: mesh %lld KiB; peak growth: streaming copy %lld KiB, read_mesh + write_mesh %lld KiB, "
              "measure_extent %lld KiB\n",
              (long long)mesh_kib, (long long)copy_kib, (long long)load_kib, (long long)measure_kib);
  ASSERT_GE(copy_kib, 0);
  ASSERT_GE(load_kib, 0);
  ASSERT_GE(measure_kib, 0);
  EXPECT_EQ(slurp(dir.file("copy.ply.zst")), slurp(dir.file("load.ply.zst")));
  EXPECT_GT(load_kib, mesh_kib * 9 / 10);        // the loaded path holds the mesh...
  EXPECT_LT(copy_kib, 24 * 1024);                // ...the copy its buffers only
  EXPECT_LT(copy_kib, mesh_kib / 2);
  EXPECT_LT(measure_kib, 16 * 1024);
}


// ---- meshflow convert, as a user runs it ----

struct Outcome {
  int status;
  std::string err;
};

Outcome convert(const TempDir& dir, const std::string& in, const std::string& out) {
  std::string command = "timeout 120 " MESHFLOW_BINARY " convert " + in + " " + out + " >/dev/null 2>" + dir.file("stderr");
  int raw = std::system(command.c_str());
  std::string err = slurp(dir.file("stderr"));
  fs::remove(dir.file("stderr"));
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, err};
}

TEST(ConvertCommand, StreamsToPlyWithTheBytesOfTheLoadedPath) {
  TempDir dir;
  for (std::string file : {"real/ogre.obj", "formats/Spider_ascii.stl", "real/igea_tristrips.ply"}) {
    SCOPED_TRACE(file);
    std::string in = shared_meshes() + "/" + file;
    write_mesh(read_mesh(in), dir.file("ref.ply.zst"));
    Outcome r = convert(dir, in, dir.file("out.ply.zst"));
    ASSERT_EQ(r.status, 0) << r.err;
    EXPECT_TRUE(slurp(dir.file("out.ply.zst")) == slurp(dir.file("ref.ply.zst")));
  }
  // Other formats still go through the loaded mesh.
  Outcome r = convert(dir, shared_meshes() + "/real/kitten.off", dir.file("k.obj"));
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(read_mesh(dir.file("k.obj")) == read_mesh(shared_meshes() + "/real/kitten.off"));
}

TEST(ConvertCommand, BadInputExitsTwoNamingTheByteAndLeavesNoFile) {
  TempDir dir;
  std::string truncated = shared_meshes() + "/malformed/elephant_truncated.ply";
  Outcome r = convert(dir, truncated, dir.file("out.ply"));
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("elephant_truncated.ply: byte 76855: unexpected end of file"), std::string::npos) << r.err;
  EXPECT_TRUE(files_in(dir).empty()) << ::testing::PrintToString(files_in(dir));
}

}  // namespace
}  // namespace meshflow::mesh
