#include "engine/remote_job.h"

#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "protocol/http_client.h"

namespace meshflow::engine {
namespace {

using nlohmann::json;

constexpr auto kUploadTimeout = std::chrono::hours(1);
constexpr auto kCallTimeout = std::chrono::seconds(30);
constexpr int kUnreachableLimit = 50;  // polls in a row without an answer before giving up

std::string error_text(const protocol::HttpResult& res) {
  json body = json::parse(res.body, nullptr, false);
  if (body.is_object() && body.contains("error") && body["error"].is_string()) return body["error"];
  return res.describe();
}

StepReport step_report(const json& step) {
  StepReport r;
  r.operation = step.value("operation", "");
  r.node = step.value("node", "");
  r.run_ms = step.value("run_ms", std::int64_t{0});
  r.wait_ms = step.value("wait_ms", std::int64_t{0});
  r.transfer_ms = step.value("transfer_ms", std::int64_t{0});
  r.update_ms = step.value("update_ms", std::int64_t{0});
  r.sent = step["sent"].is_string() ? step["sent"].get<std::string>() : "";
  r.correction_bytes = step.value("correction_bytes", std::uint64_t{0});
  r.output_bytes = step.value("output_bytes", std::uint64_t{0});
  r.is_analysis = step.value("kind", "") == "analysis";
  r.value = step["value"].is_number() ? step["value"].get<double>() : 0;
  return r;
}

bool ends_with(const std::string& text, const std::string& suffix) {
  return text.size() >= suffix.size() && text.compare(text.size() - suffix.size(), suffix.size(), suffix) == 0;
}

}  // namespace

RemoteJobResult run_on_hub(const std::string& hub_url, const std::string& workflow_path,
                           const std::string& input_path, const std::string& output_path,
                           const RemoteJobOptions& options) {
  std::string hub = hub_url;
  while (!hub.empty() && hub.back() == '/') hub.pop_back();
  if (!std::filesystem::is_regular_file(workflow_path)) throw IoError(workflow_path + ": cannot open");
  if (!std::filesystem::is_regular_file(input_path)) throw IoError(input_path + ": cannot open");
  std::vector<protocol::FormPart> form{{.name = "workflow", .file_path = workflow_path},
                                       {.name = "input", .file_path = input_path},
                                       {.name = "transfer", .value = options.transfer}};
  protocol::HttpOptions http;
  http.timeout = kUploadTimeout;
  protocol::HttpResult submitted = protocol::http_post_form(hub + "/api/jobs", form, http);
  if (submitted.status == 400 || submitted.status == 413)
    throw InvalidInput("the hub refused the job: " + error_text(submitted));
  if (!submitted.ok()) throw IoError("POST " + hub + "/api/jobs: " + submitted.describe());
  json answer = json::parse(submitted.body, nullptr, false);
  if (!answer.is_object() || !answer.contains("id") || !answer["id"].is_string())
    throw IoError("POST " + hub + "/api/jobs answered without a job id: " + submitted.body.substr(0, 200));
  RemoteJobResult result;
  result.id = answer["id"];
  std::string job_url = hub + "/api/jobs/" + result.id;
  if (options.on_submitted) options.on_submitted(job_url);

  http.timeout = kCallTimeout;
  std::size_t reported = 0;
  int unreachable = 0;
  json job;
  for (;;) {
    if (options.interrupted && options.interrupted()) {
      protocol::http_request("DELETE", job_url, {}, http);
      throw std::runtime_error("cancelled");
    }
    protocol::HttpResult res = protocol::http_request("GET", job_url, {}, http);
    if (!res.ok()) {
      // A hub that restarts comes back with the job (DESIGN §10): keep asking for a while.
      if (res.status == 0 && ++unreachable < kUnreachableLimit) {
        std::this_thread::sleep_for(options.poll_every * 5);
        continue;
      }
      throw IoError("GET " + job_url + ": " + res.describe());
    }
    unreachable = 0;
    job = json::parse(res.body, nullptr, false);
    if (!job.is_object()) throw IoError("GET " + job_url + " answered no JSON");
    const json& steps = job["steps"];
    while (steps.is_array() && reported < steps.size() && steps[reported].value("state", "") == "done") {
      if (options.on_step) options.on_step(step_report(steps[reported]));
      ++reported;
    }
    std::string state = job.value("state", "");
    if (state == "done") break;
    if (state == "failed" || state == "cancelled")
      throw IoError("job " + result.id + " " + state + ": " +
                    (job["error"].is_string() ? job["error"].get<std::string>() : std::string("no reason given")));
    std::this_thread::sleep_for(options.poll_every);
  }
  result.output_sha256 = job["output_sha256"].is_string() ? job["output_sha256"].get<std::string>() : "";
  result.elapsed_ms = job.value("elapsed_ms", std::int64_t{0});

  // The result as canonical PLY, checked against its hash; converted when OUT asks another format.
  bool canonical = ends_with(output_path, ".ply");
  std::string target = canonical ? output_path : output_path + ".download.ply";
  http.timeout = kUploadTimeout;
  std::optional<std::string> expected;
  if (!result.output_sha256.empty()) expected = result.output_sha256;
  protocol::DownloadResult got = protocol::http_download(job_url + "/output", target, expected, false, http);
  if (!got.ok()) throw IoError("GET " + job_url + "/output: " + got.describe());
  if (!canonical) {
    mesh::write_mesh(mesh::read_mesh(target), output_path);
    std::filesystem::remove(target);
  }
  return result;
}

}  // namespace meshflow::engine
