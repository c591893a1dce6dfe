// `meshflow simplify|partition|merge` as a user runs them: real processes, bounded by timeout.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

#include "mesh/generate.h"
#include "mesh/mesh_io.h"
#include "tests/support/meshes.h"

namespace meshflow::parallel {
namespace {

struct Outcome {
  int status;
  std::string err;
};

Outcome run(const meshflow::testing::TempDir& dir, const std::string& args) {
  std::string err = dir.file("stderr");
  int raw = std::system(("timeout 120 " MESHFLOW_BINARY " " + args + " >/dev/null 2>" + err).c_str());
  std::ifstream in(err);
  std::stringstream text;
  text << in.rdbuf();
  return {WIFEXITED(raw) ? WEXITSTATUS(raw) : -1, text.str()};
}

TEST(SimplifyCommand, ReportsPartsAndMergeReproducesTheResult) {
  meshflow::testing::TempDir dir;
  mesh::GenerateParams g;
  g.shape = mesh::Shape::Sphere;
  g.triangles = 20000;
  mesh::generate_mesh(g, dir.file("in.ply"));
  Outcome r = run(dir, "simplify " + dir.file("in.ply") + " -o " + dir.file("out.ply") + " --max-error 0.1 --vertices-per-part 2000"
               " --workers 2 --report " + dir.file("r.json") + " --parts-dir " + dir.file("parts"));
  ASSERT_EQ(r.status, 0) << r.err;
  std::ifstream report(dir.file("r.json"));
  std::string json((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"parts\": "), std::string::npos) << json;
  EXPECT_EQ(json.find("\"parts\": 1,"), std::string::npos) << json;
  r = run(dir, "merge " + dir.file("parts") + " -o " + dir.file("merged.ply") + " --max-error 0.1");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(mesh::read_mesh(dir.file("out.ply")) == mesh::read_mesh(dir.file("merged.ply")));
}

TEST(SimplifyCommand, RefusesBadInputClearly) {
  meshflow::testing::TempDir dir;
  std::ofstream(dir.file("bad.off")) << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n";
  Outcome r = run(dir, "simplify " + dir.file("bad.off") + " -o " + dir.file("o.ply") + " --max-error 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("bad.off"), std::string::npos) << r.err;
  r = run(dir, "simplify " + dir.file("bad.off") + " -o " + dir.file("o.ply") + " --max-error 0");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--max-error"), std::string::npos) << r.err;
  r = run(dir, "simplify " + dir.file("bad.off") + " -o " + dir.file("o.ply") + " --max-error 0.1 --nodes http://127.0.0.1:1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("not implemented"), std::string::npos) << r.err;
  r = run(dir, "merge " + dir.file("nowhere") + " -o " + dir.file("o.ply") + " --max-error 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("partition.txt"), std::string::npos) << r.err;
}

}  // namespace
}  // namespace meshflow::parallel
