// Integration tests: real `meshflow up`, `meshflow hub` and `meshflow node` processes on
// loopback, real HTTP, real meshes. Every process is stopped when its test ends.
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <thread>

#include "engine/job_journal.h"
#include "mesh/canonical_ply.h"
#include "mesh/generate.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "protocol/http_client.h"
#include "tests/support/meshes.h"
#include "tests/support/process.h"

namespace meshflow {
namespace {

using namespace meshflow::testing;
using nlohmann::json;

const char* kRepair = R"(<workflow><body>
  <if><condition><analysis><name>NumberOfComponents</name><operator>GT</operator><value>1</value></analysis></condition>
    <body><atomic><name>RemoveSmallestComponents</name></atomic></body></if>
  <atomic><name>LaplacianSmoothing</name><parameters><parameter>1</parameter></parameters></atomic>
  <while><condition><analysis><name>NumberOfBoundaryLoops</name><operator>GT</operator><value>0</value></analysis></condition>
    <body><atomic><name>FillHoles</name></atomic></body></while>
  <atomic><name>RemoveDegenerateTriangles</name></atomic>
</body></workflow>)";

// A node registered with the hub whose data folder is dir/hub; its own data in dir/NAME.
std::vector<std::string> hub_node(const std::string& hub, const TempDir& dir, const std::string& name,
                                  std::vector<std::string> extra = {}) {
  std::vector<std::string> argv{MESHFLOW_BINARY, "node", "--hub", hub, "--token-file", dir.file("hub") + "/node.token",
                                "--data", dir.file(name)};
  argv.insert(argv.end(), extra.begin(), extra.end());
  return argv;
}

// Submits a job with curl (multipart, as a browser or script would); returns its id.
std::string submit(const std::string& hub, const TempDir& dir, const std::string& xml, const std::string& mesh) {
  std::ofstream(dir.file("w.xml")) << xml;
  std::string command = "curl -s -m 60 -F workflow=@" + dir.file("w.xml") + " -F input=@" + mesh + " " + hub +
                        "/api/jobs > " + dir.file("submit.json");
  if (std::system(command.c_str()) != 0) return "";
  std::ifstream in(dir.file("submit.json"));
  json answer = json::parse(in, nullptr, false);
  return answer.is_object() ? answer.value("id", "") : "";
}

json wait_for(const std::string& hub, const std::string& id, std::chrono::seconds limit = std::chrono::seconds(120)) {
  auto deadline = std::chrono::steady_clock::now() + limit;
  json job;
  while (std::chrono::steady_clock::now() < deadline) {
    auto res = protocol::http_request("GET", hub + "/api/jobs/" + id);
    job = json::parse(res.body, nullptr, false);
    std::string state = job.is_object() ? job.value("state", "") : "";
    if (state == "done" || state == "failed" || state == "cancelled") return job;
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  return job;
}

TEST(Hub, UpRunsTheRepairWorkflowOnItsNodesSendingCorrections) {
  TempDir dir;
  ChildProcess up({MESHFLOW_BINARY, "up", "--port", "0", "--data", dir.file("data")});
  std::string hub = up.ready_url();
  ASSERT_FALSE(hub.empty());
  EXPECT_TRUE(protocol::http_request("GET", hub + "/readyz").ok());
  auto ops = json::parse(protocol::http_request("GET", hub + "/api/operations").body);
  EXPECT_EQ(ops["operations"].size(), 22u);

  std::string id = submit(hub, dir, kRepair, shared_meshes() + "/real/ogre.obj");
  ASSERT_FALSE(id.empty());
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  bool sent_correction = false;
  for (const auto& step : job["steps"])
    if (step["sent"] == "correction" && step["correction_bytes"] < step["output_bytes"]) sent_correction = true;
  EXPECT_TRUE(sent_correction) << job.dump();
  auto got = protocol::http_download(hub + "/api/jobs/" + id + "/output", dir.file("out.ply"));
  ASSERT_TRUE(got.ok()) << got.describe();
  auto m = mesh::compute_measures(mesh::read_mesh(dir.file("out.ply")));
  EXPECT_EQ(m.components, 1u);
  EXPECT_EQ(m.boundary_loops, 0u);
  EXPECT_EQ(up.stop(), 0);  // SIGTERM: nodes stopped, exit 0
}

TEST(Hub, ConditionalAndLoopWorkflowsAndBadUploads) {
  TempDir dir;
  ChildProcess up({MESHFLOW_BINARY, "up", "--port", "0", "--data", dir.file("data")});
  std::string hub = up.ready_url();
  ASSERT_FALSE(hub.empty());
  // The thesis's loop (Table 4.5): smooth while the normal instability exceeds a threshold.
  const char* loop = R"(<workflow><body>
    <atomic><name>AddNoise</name><parameters><parameter>0.3</parameter><parameter>1</parameter></parameters></atomic>
    <while><condition><analysis><name>AverageNormalInstability</name><operator>GT</operator><value>12</value></analysis></condition>
      <body><atomic><name>LaplacianSmoothing</name></atomic></body></while>
  </body></workflow>)";
  std::string id = submit(hub, dir, loop, shared_meshes() + "/real/kitten.off");
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  int smoothings = 0;
  double last = 1e9;
  for (const auto& step : job["steps"]) {
    if (step["operation"] == "LaplacianSmoothing") ++smoothings;
    if (step["operation"] == "AverageNormalInstability") last = step["value"];
  }
  EXPECT_GE(smoothings, 1);
  EXPECT_LE(last, 12.0);
  // A truncated mesh: a clear 400, and the hub keeps serving.
  std::string truncated = shared_meshes() + "/malformed/elephant_truncated.ply";
  std::ofstream(dir.file("w.xml")) << kRepair;
  std::string command = "curl -s -m 60 -o " + dir.file("bad.json") + " -w '%{http_code}' -F workflow=@" +
                        dir.file("w.xml") + " -F input=@" + truncated + " " + hub + "/api/jobs > " + dir.file("code");
  ASSERT_EQ(std::system(command.c_str()), 0);
  std::ifstream code_in(dir.file("code"));
  std::string code;
  code_in >> code;
  EXPECT_EQ(code, "400");
  std::ifstream bad(dir.file("bad.json"));
  json error = json::parse(bad, nullptr, false);
  EXPECT_NE(error.value("error", "").find("unexpected end of file"), std::string::npos) << error.dump();
  // An invalid workflow: 400 with line and column.
  std::string bad_id = submit(hub, dir, "<workflow><body><atomic><name>Smooth</name></atomic></body></workflow>",
                              shared_meshes() + "/real/kitten.off");
  EXPECT_EQ(bad_id, "");
  EXPECT_TRUE(protocol::http_request("GET", hub + "/healthz").ok());
}

TEST(Hub, AStepOnADeadNodeRunsAgainOnAnother) {
  TempDir dir;
  ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process.ready_url();
  ASSERT_FALSE(hub.empty());
  ChildProcess a(hub_node(hub, dir, "a"));
  ChildProcess b(hub_node(hub, dir, "b"));
  std::string a_url = a.ready_url(), b_url = b.ready_url();
  ASSERT_FALSE(a_url.empty());
  ASSERT_FALSE(b_url.empty());
  a.kill_now();  // registered, then gone: the hub still lists it and picks it first
  std::string id = submit(hub, dir, kRepair, shared_meshes() + "/real/stanford-bunny.obj");
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  for (const auto& step : job["steps"]) EXPECT_EQ(step["node"], b_url) << job.dump();
}

// DESIGN §9 inside a workflow: the bunny (35,947 vertices) is larger than either node takes
// (20,000), so its Simplify runs in parts on both nodes, and the next step gets the merged mesh.
// (The analysis step of the bunny: 35,947 vertices, 5 boundary loops, 1 component.)
TEST(Hub, ASimplifyLargerThanEveryNodeRunsInPartsOnTheNodes) {
  TempDir dir;
  ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process.ready_url();
  ASSERT_FALSE(hub.empty());
  ChildProcess a(hub_node(hub, dir, "a", {"--capacity", "20000"}));
  ChildProcess b(hub_node(hub, dir, "b", {"--capacity", "20000"}));
  ASSERT_FALSE(a.ready_url().empty());
  ASSERT_FALSE(b.ready_url().empty());
  const char* xml = "<workflow><body><atomic><name>Simplify</name><parameters><parameter>0.2</parameter>"
                    "</parameters></atomic><atomic><name>RemoveDegenerateTriangles</name></atomic></body></workflow>";
  const std::string input = shared_meshes() + "/real/stanford-bunny.obj";
  std::string id = submit(hub, dir, xml, input);
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  ASSERT_EQ(job["steps"].size(), 2u) << job.dump();
  EXPECT_NE(job["steps"][0]["node"].get<std::string>().find("parts on 2 nodes"), std::string::npos) << job.dump();
  auto got = protocol::http_download(hub + "/api/jobs/" + id + "/output", dir.file("out.ply"));
  ASSERT_TRUE(got.ok()) << got.describe();
  mesh::Mesh in = mesh::read_mesh(input), out = mesh::read_mesh(dir.file("out.ply"));
  auto before = mesh::compute_measures(in), after = mesh::compute_measures(out);
  EXPECT_LT(after.vertices, before.vertices / 2);
  EXPECT_GT(after.vertices, 500u);
  // The next step ran on a node, which fetched the merged mesh from the hub.
  EXPECT_EQ(job["steps"][1]["node"].get<std::string>().rfind("http://", 0), 0u) << job.dump();
  // No cracks: the parts' seams match, so the boundary and the pieces are those of the input.
  EXPECT_EQ(after.boundary_loops, before.boundary_loops);
  EXPECT_EQ(after.components, before.components);
}

// A hub that the restart tests kill outright and start again on the same port and data folder.
class RestartableHub {
 public:
  explicit RestartableHub(const TempDir& dir) : data_(dir.file("hub")) {
    start("0");
    url = process_->ready_url();
  }
  void kill() { process_->kill_now(); }
  // Kills it (if still running) and starts it again; false when it does not come up at the same URL.
  bool restart() {
    kill();
    start(url.substr(url.rfind(':') + 1));
    return process_->ready_url() == url;
  }
  std::string url;

 private:
  void start(const std::string& port) {
    process_ = std::make_unique<ChildProcess>(std::vector<std::string>{MESHFLOW_BINARY, "hub", "--port", port, "--data", data_});
  }
  std::string data_;
  std::unique_ptr<ChildProcess> process_;
};

TEST(Hub, ARestartedHubGoesOnFromTheLastFinishedStep) {
  TempDir dir;
  RestartableHub restartable(dir);
  const std::string& hub = restartable.url;
  ASSERT_FALSE(hub.empty());
  ChildProcess a(hub_node(hub, dir, "a"));
  ChildProcess b(hub_node(hub, dir, "b"));
  ASSERT_FALSE(a.ready_url().empty());
  ASSERT_FALSE(b.ready_url().empty());
  std::string xml = "<workflow><body>";
  for (int i = 0; i < 16; ++i) xml += "<atomic><name>LaplacianSmoothing</name><parameters><parameter>2</parameter></parameters></atomic>";
  xml += "</body></workflow>";
  std::string id = submit(hub, dir, xml, shared_meshes() + "/real/igea_tristrips.ply");
  ASSERT_FALSE(id.empty());
  // Wait for a few finished steps, then kill the hub outright.
  std::size_t before = 0;
  for (int i = 0; i < 600 && before < 3; ++i) {
    auto job = json::parse(protocol::http_request("GET", hub + "/api/jobs/" + id).body, nullptr, false);
    before = job.is_object() ? job["steps"].size() : 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_GE(before, 3u);
  ASSERT_TRUE(restartable.restart());
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["steps"].size(), 16u);
  auto got = protocol::http_download(hub + "/api/jobs/" + id + "/output", dir.file("out.ply"));
  ASSERT_TRUE(got.ok()) << got.describe();
  // The same result as an uninterrupted in-process run.
  std::ofstream(dir.file("w.xml")) << xml;
  std::string command = std::string(MESHFLOW_BINARY) + " run " + dir.file("w.xml") + " " + shared_meshes() +
                        "/real/igea_tristrips.ply -o " + dir.file("ref.ply") + " 2>/dev/null";
  ASSERT_EQ(std::system(command.c_str()), 0);
  EXPECT_EQ(mesh::read_mesh(dir.file("out.ply")), mesh::read_mesh(dir.file("ref.ply")));
}

// Issue 7: a resumed job's current mesh has the vertex count of the last replayed step, not the
// input's. FillHoles takes the bunny from 35,947 vertices to 36,275, above what each node takes
// (36,000), so the Simplify after it runs in parts, and must still do so when it is the first
// live step of a restarted hub: on the input's count it would go whole to a node, which refuses
// the mesh.
TEST(Hub, AResumedJobSplitsOnTheVertexCountOfItsLastReplayedStep) {
  TempDir dir;
  RestartableHub restartable(dir);
  const std::string& hub = restartable.url;
  ASSERT_FALSE(hub.empty());
  ChildProcess a(hub_node(hub, dir, "a", {"--capacity", "36000"}));
  ChildProcess b(hub_node(hub, dir, "b", {"--capacity", "36000"}));
  ASSERT_FALSE(a.ready_url().empty());
  ASSERT_FALSE(b.ready_url().empty());
  const char* xml = "<workflow><body><atomic><name>FillHoles</name></atomic><atomic><name>Simplify</name>"
                    "<parameters><parameter>0.2</parameter></parameters></atomic></body></workflow>";
  std::string id = submit(hub, dir, xml, shared_meshes() + "/real/stanford-bunny.obj");
  ASSERT_FALSE(id.empty());
  ASSERT_EQ(wait_for(hub, id)["state"], "done");
  // Back to where a hub killed between the two steps leaves the journal: FillHoles done, the
  // Simplify running, the job running. (Killing it in that window by polling is a race.)
  restartable.kill();
  {
    engine::JobJournal journal(dir.file("hub") + "/jobs.sqlite");
    std::optional<engine::JobRecord> job = journal.get(id);
    ASSERT_TRUE(job && job->steps.size() == 2);
    EXPECT_GT(job->steps[0].output_vertices, 36'000u);
    engine::StepRecord simplify = job->steps[1];
    simplify.state = "running";
    journal.put_step(id, simplify);
    journal.set_state(id, engine::JobState::Running);
  }
  ASSERT_TRUE(restartable.restart());
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  ASSERT_EQ(job["steps"].size(), 2u) << job.dump();
  EXPECT_NE(job["steps"][1]["node"].get<std::string>().find("parts on 2 nodes"), std::string::npos) << job.dump();
}

// The thesis's conditional workflow (Table 4.4): remove components only when there are
// several, fill holes only when there are some.
const char* kConditional = R"(<workflow><body>
  <if><condition><analysis><name>NumberOfComponents</name><operator>GT</operator><value>1</value></analysis></condition>
    <body><atomic><name>RemoveSmallestComponents</name></atomic></body></if>
  <if><condition><analysis><name>NumberOfBoundaryLoops</name><operator>GT</operator><value>0</value></analysis></condition>
    <body><atomic><name>FillHoles</name></atomic></body></if>
</body></workflow>)";

std::string slurp(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

// Runs a shell command, bounded by `timeout` seconds; returns its exit status.
int shell(const std::string& command, int timeout = 120) {
  int status = std::system(("timeout " + std::to_string(timeout) + " " + command).c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

json get_json(const std::string& url) {
  return json::parse(protocol::http_request("GET", url).body, nullptr, false);
}

TEST(Hub, RunWithHubFollowsTheJobAndBothTransferModesGiveTheSameOutput) {
  TempDir dir;
  ChildProcess up({MESHFLOW_BINARY, "up", "--port", "0", "--data", dir.file("data")});
  std::string hub = up.ready_url();
  ASSERT_FALSE(hub.empty());
  std::ofstream(dir.file("c.xml")) << kConditional;
  std::string input = shared_meshes() + "/real/ogre.obj";
  std::string mf = MESHFLOW_BINARY;
  ASSERT_EQ(shell(mf + " run " + dir.file("c.xml") + " " + input + " -o " + dir.file("local.ply") + " 2>/dev/null"), 0);
  ASSERT_EQ(shell(mf + " run " + dir.file("c.xml") + " " + input + " -o " + dir.file("hub.ply") + " --hub " + hub +
                  " 2>" + dir.file("hub.err")),
            0)
      << slurp(dir.file("hub.err"));
  ASSERT_EQ(shell(mf + " run " + dir.file("c.xml") + " " + input + " -o " + dir.file("whole.off") + " --hub " + hub +
                  " --transfer output 2>" + dir.file("whole.err")),
            0)
      << slurp(dir.file("whole.err"));
  // Progress: one line per step, naming the node; the two conditions held on the ogre.
  std::string progress = slurp(dir.file("hub.err"));
  EXPECT_NE(progress.find("NumberOfComponents = 44 on http://"), std::string::npos) << progress;
  EXPECT_NE(progress.find("RemoveSmallestComponents on http://"), std::string::npos) << progress;
  EXPECT_NE(progress.find("FillHoles on http://"), std::string::npos) << progress;
  EXPECT_NE(progress.find("sent the correction"), std::string::npos) << progress;
  EXPECT_NE(slurp(dir.file("whole.err")).find("sent the output"), std::string::npos) << slurp(dir.file("whole.err"));
  // The same mesh, bit for bit, in-process, through the hub, and with whole-mesh transfers.
  mesh::Mesh local = mesh::read_mesh(dir.file("local.ply"));
  EXPECT_EQ(mesh::read_mesh(dir.file("hub.ply")), local);
  EXPECT_EQ(mesh::read_mesh(dir.file("whole.off")), local);
  auto m = mesh::compute_measures(local);
  EXPECT_EQ(m.components, 1u);
  EXPECT_EQ(m.boundary_loops, 0u);
  // A workflow the hub refuses: exit 2 with line and column.
  std::ofstream(dir.file("bad.xml")) << "<workflow><body>\n<atomic><name>Smooth</name></atomic></body></workflow>";
  EXPECT_EQ(shell(mf + " run " + dir.file("bad.xml") + " " + input + " -o " + dir.file("x.ply") + " --hub " + hub +
                  " 2>" + dir.file("bad.err")),
            2);
  EXPECT_NE(slurp(dir.file("bad.err")).find(":2:"), std::string::npos) << slurp(dir.file("bad.err"));
}

TEST(Hub, FetchesAnInputUrlOnlyWhereAllowed) {
  TempDir dir;
  std::ofstream(dir.file("w.xml")) << kConditional;
  auto post = [&](const std::string& hub, const std::string& url, const std::string& out) {
    std::string command = "curl -s -m 60 -o " + dir.file(out) + " -w '%{http_code}' -F workflow=@" + dir.file("w.xml") +
                          " -F input_url=" + url + " " + hub + "/api/jobs";
    FILE* pipe = popen(command.c_str(), "r");
    char code[8] = {0};
    if (pipe) {
      std::fgets(code, sizeof code, pipe);
      pclose(pipe);
    }
    return std::string(code);
  };
  {
    // A hub started without --allow-private-fetch refuses loopback, private and non-http URLs.
    ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("strict")});
    std::string hub = hub_process.ready_url();
    ASSERT_FALSE(hub.empty());
    EXPECT_EQ(post(hub, hub + "/api/jobs/0/input", "a.json"), "400");
    EXPECT_NE(slurp(dir.file("a.json")).find("loopback or private"), std::string::npos) << slurp(dir.file("a.json"));
    EXPECT_EQ(post(hub, "http://10.1.2.3/mesh.ply", "b.json"), "400");
    EXPECT_EQ(post(hub, "http://[::1]:9/mesh.ply", "c.json"), "400");
    EXPECT_EQ(post(hub, "file:///etc/passwd", "d.json"), "400");
    EXPECT_NE(slurp(dir.file("d.json")).find("http"), std::string::npos) << slurp(dir.file("d.json"));
  }
  // With the flag, the hub fetches the URL itself (here: another job's canonical input).
  ChildProcess up({MESHFLOW_BINARY, "up", "--port", "0", "--data", dir.file("open"), "--allow-private-fetch"});
  std::string hub = up.ready_url();
  ASSERT_FALSE(hub.empty());
  std::string first = submit(hub, dir, kConditional, shared_meshes() + "/defects/elephant-with-holes.off");
  ASSERT_EQ(wait_for(hub, first)["state"], "done");
  ASSERT_EQ(post(hub, hub + "/api/jobs/" + first + "/input", "e.json"), "202") << slurp(dir.file("e.json"));
  std::string second = json::parse(slurp(dir.file("e.json"))).value("id", "");
  json job = wait_for(hub, second);
  ASSERT_EQ(job["state"], "done") << job.dump();
  EXPECT_EQ(job["input_url"], hub + "/api/jobs/" + first + "/input");
  EXPECT_EQ(job["output_sha256"], wait_for(hub, first)["output_sha256"]);
  // A URL that is not a mesh: the job fails with a reason.
  ASSERT_EQ(post(hub, hub + "/healthz", "f.json"), "202");
  json bad = wait_for(hub, json::parse(slurp(dir.file("f.json"))).value("id", ""));
  EXPECT_EQ(bad["state"], "failed");
  EXPECT_NE(bad.value("error", "").find("is not a mesh"), std::string::npos) << bad.dump();
}

// Issue 7: the hub canonicalises an upload by streaming it, never loading it. A gzipped OBJ
// whose vertices and faces interleave (quads) becomes the canonical input of
// write_mesh(read_mesh()), byte for byte; a damaged upload gets the reader's error (400) and
// leaves no job behind.
TEST(Hub, AnUploadIsCanonicalisedByStreamingAndADamagedOneLeavesNothing) {
  TempDir dir;
  ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process.ready_url();
  ASSERT_FALSE(hub.empty());
  ChildProcess a(hub_node(hub, dir, "a"));
  ASSERT_FALSE(a.ready_url().empty());
  {
    std::ofstream obj(dir.file("strip.obj"));
    for (int i = 0; i < 50; ++i) {
      obj << "v " << i << " 0 0\nv " << i << " 1 " << (i % 3) * 0.1 << "\n";
      if (i > 0) obj << "f " << 2 * i - 1 << " " << 2 * i + 1 << " " << 2 * i + 2 << " " << 2 * i << "\n";
    }
  }
  ASSERT_EQ(shell("gzip -k " + dir.file("strip.obj")), 0);
  const char* xml = "<workflow><body><atomic><name>LaplacianSmoothing</name></atomic></body></workflow>";
  std::string id = submit(hub, dir, xml, dir.file("strip.obj.gz"));
  ASSERT_FALSE(id.empty());
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  mesh::Mesh original = mesh::read_mesh(dir.file("strip.obj"));
  ASSERT_EQ(original.num_triangles(), 98u);
  auto input = protocol::http_download(hub + "/api/jobs/" + id + "/input", dir.file("input.ply.zst"),
                                       mesh::mesh_sha256(original), true);
  ASSERT_TRUE(input.ok()) << input.describe();
  mesh::write_mesh(original, dir.file("ref.ply.zst"));
  EXPECT_TRUE(slurp(dir.file("input.ply.zst")) == slurp(dir.file("ref.ply.zst")));
  // The output, decompressed by the hub's streaming copy, is the canonical PLY of its hash.
  auto output = protocol::http_download(hub + "/api/jobs/" + id + "/output", dir.file("out.ply"),
                                        job["output_sha256"].get<std::string>());
  ASSERT_TRUE(output.ok()) << output.describe();
  EXPECT_EQ(mesh::read_mesh(dir.file("out.ply")).num_vertices(), original.num_vertices());

  std::string bytes = slurp(dir.file("strip.obj.gz"));
  std::ofstream(dir.file("cut.obj.gz"), std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  std::ofstream(dir.file("w.xml")) << xml;
  std::string command = "curl -s -m 60 -o " + dir.file("bad.json") + " -w '%{http_code}' -F workflow=@" +
                        dir.file("w.xml") + " -F input=@" + dir.file("cut.obj.gz") + " " + hub + "/api/jobs > " +
                        dir.file("code");
  ASSERT_EQ(std::system(command.c_str()), 0);
  EXPECT_EQ(slurp(dir.file("code")), "400");
  json error = json::parse(slurp(dir.file("bad.json")), nullptr, false);
  EXPECT_NE(error.value("error", "").find("truncated gzip stream"), std::string::npos) << error.dump();
  std::vector<std::string> jobs;
  for (const auto& entry : std::filesystem::directory_iterator(dir.file("hub") + "/jobs"))
    jobs.push_back(entry.path().filename().string());
  EXPECT_EQ(jobs, std::vector<std::string>{id});
  EXPECT_TRUE(protocol::http_request("GET", hub + "/healthz").ok());
}

// The node answers every /run with a task URL at once (--answer-within-ms 0): the job only
// finishes if the engine polls the tasks. Cancelling a job stops its running task.
TEST(Hub, LongRunsAnswerWithATaskThatTheEnginePollsAndCancelStopsThem) {
  TempDir dir;
  ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process.ready_url();
  ASSERT_FALSE(hub.empty());
  ChildProcess node(hub_node(hub, dir, "n", {"--answer-within-ms", "0"}));
  std::string node_url = node.ready_url();
  ASSERT_FALSE(node_url.empty());
  std::string id = submit(hub, dir, kRepair, shared_meshes() + "/defects/elephant-with-holes.off");
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  // Straight to the node: 202 and a task that ends with the result.
  std::string input = hub + "/api/jobs/" + id + "/input";
  protocol::HttpOptions http;
  http.bearer_token = slurp(dir.file("hub") + "/node.token").substr(0, 64);
  auto res = protocol::http_request("POST", node_url + "/run/NumberOfBoundaryLoops", json{{"input", input}}.dump(), http);
  ASSERT_EQ(res.status, 202) << res.describe();
  std::string task = json::parse(res.body).value("task", "");
  ASSERT_EQ(task.rfind(node_url + "/tasks/", 0), 0u) << res.body;
  json state;
  for (int i = 0; i < 200; ++i) {
    state = get_json(task);
    if (state.value("state", "") != "running") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  EXPECT_EQ(state["state"], "done") << state.dump();
  EXPECT_EQ(state["result"]["value"], 106);

  // A long smoothing, cancelled while it runs: the job ends as cancelled within seconds, and
  // progress events showed the step running, then the end.
  const char* slow = "<workflow><body><atomic><name>LaplacianSmoothing</name><parameters>"
                     "<parameter>10000</parameter></parameters></atomic></body></workflow>";
  std::string long_id = submit(hub, dir, slow, shared_meshes() + "/real/igea_tristrips.ply");
  ASSERT_FALSE(long_id.empty());
  ChildProcess events({"/usr/bin/curl", "-sN", "-m", "60", "-o", dir.file("events.txt"),
                       hub + "/api/jobs/" + long_id + "/events"});
  bool running = false;
  for (int i = 0; i < 1500 && !running; ++i) {  // up to 30 s on a loaded machine
    json now = get_json(hub + "/api/jobs/" + long_id);
    running = now.is_object() && !now["steps"].empty() && now["steps"][0]["state"] == "running";
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(running);
  // The event stream has connected and seen the step run before we cancel (curl may start late
  // on a loaded machine).
  for (int i = 0; i < 200 && slurp(dir.file("events.txt")).find("\"state\":\"running\"") == std::string::npos; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  auto cancelled_at = std::chrono::steady_clock::now();
  EXPECT_EQ(protocol::http_request("DELETE", hub + "/api/jobs/" + long_id).status, 202);
  json ended = wait_for(hub, long_id, std::chrono::seconds(30));
  EXPECT_EQ(ended["state"], "cancelled") << ended.dump();
  EXPECT_LT(std::chrono::steady_clock::now() - cancelled_at, std::chrono::seconds(10));
  EXPECT_EQ(ended["steps"][0]["state"], "cancelled") << ended.dump();
  for (int i = 0; i < 100 && slurp(dir.file("events.txt")).find("\"cancelled\"") == std::string::npos; ++i)
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  events.stop();
  std::string stream = slurp(dir.file("events.txt"));
  EXPECT_NE(stream.find("data: {"), std::string::npos) << stream;
  EXPECT_NE(stream.find("\"state\":\"running\""), std::string::npos) << stream;
  EXPECT_NE(stream.find("\"state\":\"cancelled\""), std::string::npos) << stream;
  // The node stopped the smoothing: it answers at once and its task says cancelled.
  EXPECT_TRUE(protocol::http_request("GET", node_url + "/healthz").ok());
}

TEST(Hub, ASimplifyInPartsIsCancelledBetweenPartsAndLeavesNoPartFiles) {
  TempDir dir;
  mesh::GenerateParams g;
  g.shape = mesh::Shape::Terrain;
  g.triangles = 1000000;  // 500k vertices: 250 parts of 2,000 on nodes that take 4,000
  mesh::generate_mesh(g, dir.file("terrain.ply"));
  ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process.ready_url();
  ASSERT_FALSE(hub.empty());
  ChildProcess a(hub_node(hub, dir, "a", {"--capacity", "4000"}));
  ChildProcess b(hub_node(hub, dir, "b", {"--capacity", "4000"}));
  ASSERT_FALSE(a.ready_url().empty());
  ASSERT_FALSE(b.ready_url().empty());
  const char* xml = "<workflow><body><atomic><name>Simplify</name><parameters><parameter>0.2</parameter>"
                    "</parameters></atomic></body></workflow>";
  std::string id = submit(hub, dir, xml, dir.file("terrain.ply"));
  ASSERT_FALSE(id.empty());
  bool in_parts = false;  // the step's node label shows the parts being simplified
  for (int i = 0; i < 3000 && !in_parts; ++i) {
    json now = get_json(hub + "/api/jobs/" + id);
    in_parts = now.is_object() && !now["steps"].empty() &&
               now["steps"][0]["node"].get<std::string>().find("parts ") != std::string::npos &&
               now["steps"][0]["node"].get<std::string>().find(" - parts") != std::string::npos;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(in_parts);
  auto cancelled_at = std::chrono::steady_clock::now();
  EXPECT_EQ(protocol::http_request("DELETE", hub + "/api/jobs/" + id).status, 202);
  json ended = wait_for(hub, id, std::chrono::seconds(60));
  EXPECT_EQ(ended["state"], "cancelled") << ended.dump();
  EXPECT_LT(std::chrono::steady_clock::now() - cancelled_at, std::chrono::seconds(10));
  EXPECT_FALSE(std::filesystem::exists(dir.file("hub") + "/jobs/" + id + "/split/split-1")) << "part files left behind";
}

TEST(Hub, ANodeKilledMidStepIsReplacedAndTheJobFinishes) {
  TempDir dir;
  ChildProcess hub_process({MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process.ready_url();
  ASSERT_FALSE(hub.empty());
  std::map<std::string, std::unique_ptr<ChildProcess>> nodes;
  for (const char* name : {"a", "b"}) {
    auto node = std::make_unique<ChildProcess>(hub_node(hub, dir, name));
    std::string url = node->ready_url();
    ASSERT_FALSE(url.empty());
    nodes[url] = std::move(node);
  }
  // A check and a long smoothing: the plan puts them on different nodes.
  const char* xml = "<workflow><body>"
                    "<if><condition><analysis><name>IsManifold</name></analysis></condition><body/></if>"
                    "<atomic><name>LaplacianSmoothing</name><parameters><parameter>2000</parameter></parameters></atomic>"
                    "</body></workflow>";
  std::string id = submit(hub, dir, xml, shared_meshes() + "/real/dragon_100k.ply");
  ASSERT_FALSE(id.empty());
  std::string victim;
  for (int i = 0; i < 500 && victim.empty(); ++i) {
    json now = get_json(hub + "/api/jobs/" + id);
    if (now.is_object())
      for (const auto& step : now["steps"])
        if (step["operation"] == "LaplacianSmoothing" && step["state"] == "running") victim = step["node"];
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  ASSERT_TRUE(nodes.count(victim)) << victim;
  std::this_thread::sleep_for(std::chrono::milliseconds(200));  // well inside the step
  nodes[victim]->kill_now();
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  const json& last = job["steps"].back();
  EXPECT_EQ(last["operation"], "LaplacianSmoothing");
  EXPECT_NE(last["node"], victim) << job.dump();
  // The result is the one an uninterrupted run gives.
  auto got = protocol::http_download(hub + "/api/jobs/" + id + "/output", dir.file("out.ply"));
  ASSERT_TRUE(got.ok()) << got.describe();
  std::ofstream(dir.file("w.xml")) << xml;
  ASSERT_EQ(shell(std::string(MESHFLOW_BINARY) + " run " + dir.file("w.xml") + " " + shared_meshes() +
                  "/real/dragon_100k.ply -o " + dir.file("ref.ply") + " 2>/dev/null"),
            0);
  EXPECT_EQ(mesh::read_mesh(dir.file("out.ply")), mesh::read_mesh(dir.file("ref.ply")));
}

// DESIGN §6: a receiver whose corrected mesh does not have the producer's hash fetches the whole
// output instead, and never keeps the mismatching mesh.
TEST(Hub, AnUpdateWhoseHashDiffersFallsBackToTheWholeOutput) {
  TempDir dir;
  ChildProcess up({MESHFLOW_BINARY, "up", "--port", "0", "--data", dir.file("data")});
  std::string hub = up.ready_url();
  ASSERT_FALSE(hub.empty());
  std::string id = submit(hub, dir, kConditional, shared_meshes() + "/real/kitten.off");
  ASSERT_EQ(wait_for(hub, id)["state"], "done");
  json services = get_json(hub + "/api/services")["services"];
  ASSERT_EQ(services.size(), 2u);
  std::string a = services[0]["url"], b = services[1]["url"];
  protocol::HttpOptions http;
  http.bearer_token = slurp(dir.file("data") + "/node.token").substr(0, 64);
  std::string input = hub + "/api/jobs/" + id + "/input";
  // On A: two different results of the same input.
  auto smooth = json::parse(protocol::http_request("POST", a + "/run/LaplacianSmoothing",
                                                   json{{"input", input}}.dump(), http).body);
  auto noisy = json::parse(protocol::http_request("POST", a + "/run/AddNoise",
                                                  json{{"input", input}, {"params", {{"seed", 7}}}}.dump(), http).body);
  ASSERT_TRUE(smooth.contains("correction")) << smooth.dump();
  ASSERT_TRUE(noisy.contains("output")) << noisy.dump();
  std::string base = smooth["base_sha256"];
  // B holds the input; it is told that the smoothing's correction yields the noisy mesh.
  ASSERT_TRUE(protocol::http_request("POST", b + "/download", json{{"url", input}}.dump(), http).ok());
  auto update = protocol::http_request(
      "POST", b + "/update",
      json{{"base", base}, {"correction", smooth["correction"]}, {"result", noisy["output"]},
           {"result_sha256", noisy["sha256"]}}.dump(),
      http);
  ASSERT_EQ(update.status, 202) << update.describe();
  json entry;
  for (int i = 0; i < 500; ++i) {
    entry = get_json(b + "/cache/" + noisy["sha256"].get<std::string>());
    if (entry.value("state", "") != "pending") break;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  EXPECT_EQ(entry["state"], "ready") << entry.dump();
  EXPECT_EQ(entry["how"], "update-fallback") << entry.dump();
  EXPECT_NE(entry.value("error", "").find("not the producer's"), std::string::npos) << entry.dump();
  EXPECT_EQ(entry["bytes"], noisy["output_bytes"].get<std::uint64_t>() + smooth["correction_bytes"].get<std::uint64_t>());
  // B has the noisy mesh (an analysis runs on it by hash) and never stored the smoothed one.
  auto count = protocol::http_request("POST", b + "/run/NumberOfVertices",
                                      json{{"input", noisy["sha256"]}}.dump(), http);
  EXPECT_TRUE(count.ok()) << count.describe();
  EXPECT_EQ(protocol::http_request("GET", b + "/cache/" + smooth["sha256"].get<std::string>()).status, 404);
  // Nodes fetch only from the hub and registered nodes; their routes need the node token, and
  // so does registering with the hub.
  auto stranger = protocol::http_request("POST", b + "/download", json{{"url", "http://127.0.0.2:9/m.ply.zst"}}.dump(), http);
  EXPECT_EQ(stranger.status, 403) << stranger.describe();
  EXPECT_NE(stranger.body.find("refusing to fetch from http://127.0.0.2:9"), std::string::npos) << stranger.body;
  EXPECT_EQ(protocol::http_request("POST", b + "/download", json{{"url", input}}.dump()).status, 401);
  EXPECT_EQ(protocol::http_request("POST", hub + "/api/services", json{{"url", b}}.dump()).status, 401);
}

}  // namespace
}  // namespace meshflow
