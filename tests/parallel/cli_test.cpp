// `meshflow simplify|partition|merge` as a user runs them: real processes, bounded by timeout.
#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "mesh/generate.h"
#include "mesh/mesh_io.h"
#include "tests/support/meshes.h"
#include "tests/support/process.h"

namespace meshflow::parallel {
namespace {

using mesh::Mesh;

struct Outcome {
  int status;
  std::string err;
};

// DIR/in.ply: a generated mesh.
void generate_input(const meshflow::testing::TempDir& dir, mesh::Shape shape, std::uint64_t triangles) {
  mesh::GenerateParams g;
  g.shape = shape;
  g.triangles = triangles;
  mesh::generate_mesh(g, dir.file("in.ply"));
}

// An integer field of a --report file's text, -1 when missing.
long report_number(const std::string& json, const std::string& key) {
  std::size_t at = json.find("\"" + key + "\": ");
  return at == std::string::npos ? -1L : std::atol(json.c_str() + at + key.size() + 4);
}

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
  generate_input(dir, mesh::Shape::Sphere, 20000);
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
  std::ofstream(dir.file("ok.off")) << "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
  r = run(dir, "simplify " + dir.file("ok.off") + " -o " + dir.file("o.ply") + " --max-error 0.1 --nodes http://127.0.0.1:1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("http://127.0.0.1:1 is not a reachable mesh node"), std::string::npos) << r.err;
  r = run(dir, "merge " + dir.file("nowhere") + " -o " + dir.file("o.ply") + " --max-error 0.1");
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("partition.txt"), std::string::npos) << r.err;
}

// Two real nodes on loopback simplify the parts (POST /parts/simplify) by the Rem scheme, the
// Rem files carried over HTTP: the result is the bytes local worker processes give, with one
// node as with two; with --fixed-seams too.
TEST(SimplifyCommand, NodesGiveTheSameResultAsLocalWorkers) {
  meshflow::testing::TempDir dir;
  generate_input(dir, mesh::Shape::Terrain, 30000);
  meshflow::testing::ChildProcess a({MESHFLOW_BINARY, "node", "--listen", "127.0.0.1:0", "--data", dir.file("a")});
  meshflow::testing::ChildProcess b({MESHFLOW_BINARY, "node", "--listen", "127.0.0.1:0", "--data", dir.file("b"),
                                     "--answer-within-ms", "1"});  // b answers with a task to poll
  std::string url_a = a.ready_url(), url_b = b.ready_url();
  ASSERT_FALSE(url_a.empty());
  ASSERT_FALSE(url_b.empty());
  const std::string common = dir.file("in.ply") + " --max-error 0.1 --vertices-per-part 3000";
  Outcome r = run(dir, "simplify " + common + " -o " + dir.file("local.ply") + " --workers 2");
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir, "simplify " + common + " -o " + dir.file("two.ply") + " --nodes " + url_a + "," + url_b + " --report " + dir.file("r.json"));
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir, "simplify " + common + " -o " + dir.file("one.ply") + " --nodes " + url_b);
  ASSERT_EQ(r.status, 0) << r.err;
  Mesh local = mesh::read_mesh(dir.file("local.ply"));
  EXPECT_LT(local.positions.size(), 15000u / 2);
  EXPECT_TRUE(mesh::read_mesh(dir.file("two.ply")) == local);
  EXPECT_TRUE(mesh::read_mesh(dir.file("one.ply")) == local);
  std::ifstream report(dir.file("r.json"));
  std::string json((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  EXPECT_NE(json.find("\"vertices_in\": "), std::string::npos) << json;  // the nodes' stats came back
  EXPECT_EQ(json.find("\"vertices_in\": 0,"), std::string::npos) << json;
  auto number = [&](const std::string& key) { return report_number(json, key); };
  EXPECT_GT(number("shared_removed_by_half_edge_collapses"), 0) << json;  // the nodes made Rem files
  EXPECT_EQ(number("shared_removed_by_half_edge_collapses"), number("shared_removed_by_replay")) << json;
  r = run(dir, "simplify " + common + " -o " + dir.file("local-fixed.ply") + " --workers 2 --fixed-seams");
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir, "simplify " + common + " -o " + dir.file("two-fixed.ply") + " --nodes " + url_a + "," + url_b + " --fixed-seams");
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(mesh::read_mesh(dir.file("two-fixed.ply")) == mesh::read_mesh(dir.file("local-fixed.ply")));
  EXPECT_FALSE(mesh::read_mesh(dir.file("two-fixed.ply")) == local);
  // A node refuses a part file it cannot read, naming it.
  std::ofstream(dir.file("junk.mfp")) << "MFPART1\n";
  std::string body = R"({"vertices": ")" + url_a + R"(/nowhere.mfp", "max_error_abs": 0.1})";
  int raw = std::system(("curl -s -m 20 -o " + dir.file("answer") + " -w '%{http_code}' -d '" + body + "' " + url_a +
                         "/parts/simplify > " + dir.file("code")).c_str());
  ASSERT_EQ(raw, 0);
  std::ifstream code(dir.file("code"));
  std::string status;
  code >> status;
  EXPECT_EQ(status[0], '5') << status;  // the fetch failed: a 5xx naming the URL
  std::ifstream answer(dir.file("answer"));
  std::string text((std::istreambuf_iterator<char>(answer)), std::istreambuf_iterator<char>());
  EXPECT_NE(text.find("nowhere.mfp"), std::string::npos) << text;
  auto post = [&](const std::string& request) {
    int rc = std::system(("curl -s -m 20 -o " + dir.file("answer") + " -w '%{http_code}' -d '" + request + "' " + url_a +
                          "/parts/simplify > " + dir.file("code")).c_str());
    EXPECT_EQ(rc, 0);
    std::ifstream c(dir.file("code")), a(dir.file("answer"));
    std::string s, t((std::istreambuf_iterator<char>(a)), std::istreambuf_iterator<char>());
    c >> s;
    return std::pair{s, t};
  };
  EXPECT_EQ(post(R"({"vertices": ")" + url_a + R"(/x.mfp", "max_error_abs": 0})").first, "400");
  // Rem files without the part's number; a list entry without its part number.
  auto [rem_status, rem_text] = post(R"({"vertices": ")" + url_a + R"(/x.mfp", "max_error_abs": 1, "removed": [{"from_part": 1, "url": "http://127.0.0.1:1/r"}]})");
  EXPECT_EQ(rem_status, "400");
  EXPECT_NE(rem_text.find("'part'"), std::string::npos) << rem_text;
  std::tie(rem_status, rem_text) = post(R"({"vertices": ")" + url_a + R"(/x.mfp", "max_error_abs": 1, "part": 0, "unprocessed": [{"url": "http://127.0.0.1:1/r"}]})");
  EXPECT_EQ(rem_status, "400");
  EXPECT_NE(rem_text.find("unprocessed"), std::string::npos) << rem_text;
}

// Local worker processes follow the Rem scheme: each part's outgoing Rem files are in the
// parts folder, the report counts the shared vertices removed on seams and replayed (the same
// number: every logged removal has one partner), and 1 or 2 workers give the same mesh.
TEST(SimplifyCommand, WorkerProcessesExchangeRemFiles) {
  meshflow::testing::TempDir dir;
  generate_input(dir, mesh::Shape::Terrain, 30000);
  const std::string common = dir.file("in.ply") + " --max-error 0.1 --vertices-per-part 3000";
  for (const char* workers : {"1", "2"}) {
    Outcome r = run(dir, "simplify " + common + " -o " + dir.file(std::string("w") + workers + ".ply") + " --workers " +
                             workers + " --report " + dir.file("r.json") + " --parts-dir " + dir.file(std::string("p") + workers));
    ASSERT_EQ(r.status, 0) << r.err;
  }
  EXPECT_TRUE(mesh::read_mesh(dir.file("w1.ply")) == mesh::read_mesh(dir.file("w2.ply")));
  std::ifstream report(dir.file("r.json"));
  std::string json((std::istreambuf_iterator<char>(report)), std::istreambuf_iterator<char>());
  auto number = [&](const std::string& key) { return report_number(json, key); };
  EXPECT_GT(number("shared_removed_by_half_edge_collapses"), 0) << json;
  EXPECT_EQ(number("shared_removed_by_half_edge_collapses"), number("shared_removed_by_replay")) << json;
  int rem_files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir.file("p2")))
    rem_files += entry.path().filename().string().rfind("rem-", 0) == 0;
  EXPECT_GT(rem_files, 0);
}

// A node that answers /service.json but drops every /parts/simplify connection: its parts go
// to the other node; with no other node the run fails naming it.
TEST(SimplifyCommand, PartsOfANodeThatStopsAnsweringGoElsewhere) {
  meshflow::testing::TempDir dir;
  generate_input(dir, mesh::Shape::Sphere, 20000);
  std::ofstream(dir.file("stub.py")) << R"(import http.server, socketserver, sys
class H(http.server.BaseHTTPRequestHandler):
    def do_GET(self):
        self.send_response(200); self.send_header('Content-Type', 'application/json'); self.end_headers(); self.wfile.write(b'{}')
    def do_POST(self):
        self.close_connection = True; self.connection.close()
    def log_message(self, *a): pass
s = socketserver.TCPServer(('127.0.0.1', 0), H)
print('stub ready at http://127.0.0.1:%d' % s.server_address[1], flush=True)
s.serve_forever()
)";
  meshflow::testing::ChildProcess stub({"/usr/bin/python3", dir.file("stub.py")});
  meshflow::testing::ChildProcess node({MESHFLOW_BINARY, "node", "--listen", "127.0.0.1:0", "--data", dir.file("n")});
  std::string stub_url = stub.ready_url(), node_url = node.ready_url();
  ASSERT_FALSE(stub_url.empty());
  ASSERT_FALSE(node_url.empty());
  const std::string common = dir.file("in.ply") + " --max-error 0.1 --vertices-per-part 2000";
  Outcome r = run(dir, "simplify " + common + " -o " + dir.file("local.ply") + " --workers 1");
  ASSERT_EQ(r.status, 0) << r.err;
  r = run(dir, "simplify " + common + " -o " + dir.file("nodes.ply") + " --nodes " + stub_url + "," + node_url);
  ASSERT_EQ(r.status, 0) << r.err;
  EXPECT_TRUE(mesh::read_mesh(dir.file("nodes.ply")) == mesh::read_mesh(dir.file("local.ply")));
  r = run(dir, "simplify " + common + " -o " + dir.file("none.ply") + " --nodes " + stub_url);
  EXPECT_EQ(r.status, 1);
  EXPECT_NE(r.err.find("every node stopped answering: " + stub_url), std::string::npos) << r.err;
}

}  // namespace
}  // namespace meshflow::parallel
