// Integration tests: real `meshflow up`, `meshflow hub` and `meshflow node` processes on
// loopback, real HTTP, real meshes. Every process is stopped when its test ends.
#include <gtest/gtest.h>

#include <chrono>
#include <fstream>
#include <nlohmann/json.hpp>
#include <thread>

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
  std::string token = dir.file("hub") + "/node.token";
  ChildProcess a({MESHFLOW_BINARY, "node", "--hub", hub, "--token-file", token, "--data", dir.file("a")});
  ChildProcess b({MESHFLOW_BINARY, "node", "--hub", hub, "--token-file", token, "--data", dir.file("b")});
  std::string a_url = a.ready_url(), b_url = b.ready_url();
  ASSERT_FALSE(a_url.empty());
  ASSERT_FALSE(b_url.empty());
  a.kill_now();  // registered, then gone: the hub still lists it and picks it first
  std::string id = submit(hub, dir, kRepair, shared_meshes() + "/real/stanford-bunny.obj");
  json job = wait_for(hub, id);
  ASSERT_EQ(job["state"], "done") << job.dump();
  for (const auto& step : job["steps"]) EXPECT_EQ(step["node"], b_url) << job.dump();
}

TEST(Hub, ARestartedHubGoesOnFromTheLastFinishedStep) {
  TempDir dir;
  auto hub_process = std::make_unique<ChildProcess>(
      std::vector<std::string>{MESHFLOW_BINARY, "hub", "--port", "0", "--data", dir.file("hub")});
  std::string hub = hub_process->ready_url();
  ASSERT_FALSE(hub.empty());
  std::string port = hub.substr(hub.rfind(':') + 1);
  std::string token = dir.file("hub") + "/node.token";
  ChildProcess a({MESHFLOW_BINARY, "node", "--hub", hub, "--token-file", token, "--data", dir.file("a")});
  ChildProcess b({MESHFLOW_BINARY, "node", "--hub", hub, "--token-file", token, "--data", dir.file("b")});
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
  hub_process->kill_now();
  hub_process = std::make_unique<ChildProcess>(
      std::vector<std::string>{MESHFLOW_BINARY, "hub", "--port", port, "--data", dir.file("hub")});
  ASSERT_EQ(hub_process->ready_url(), hub);
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

}  // namespace
}  // namespace meshflow
