#include "engine/http_node_client.h"

#include <chrono>
#include <nlohmann/json.hpp>
#include <thread>

#include "mesh/errors.h"
#include "protocol/http_client.h"

namespace meshflow::engine {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr auto kPollEvery = std::chrono::milliseconds(20);
constexpr auto kStepTimeout = std::chrono::hours(2);
constexpr auto kUpdateTimeout = std::chrono::minutes(30);

std::int64_t ms_since(Clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start).count();
}

}  // namespace

struct HttpNodeClient::Answer {
  std::string node;
  json body;
};

HttpNodeClient::HttpNodeClient(HttpNodeOptions options, std::string input_url, std::string input_sha256)
    : options_(std::move(options)), current_url_(std::move(input_url)), current_sha_(std::move(input_sha256)) {}

void HttpNodeClient::broadcast_input() {
  protocol::HttpOptions http;
  http.timeout = std::chrono::seconds(30);
  http.bearer_token = options_.token;
  std::string body = json{{"url", current_url_}, {"sha256", current_sha_}}.dump();
  for (const auto& node : options_.nodes) protocol::http_request("POST", node + "/download", body, http);
}

HttpNodeClient::Answer HttpNodeClient::run_on_some_node(const std::string& operation, const std::string& body) {
  for (;;) {
    if (options_.cancelled && options_.cancelled()) throw std::runtime_error("cancelled");
    std::optional<std::string> node = options_.pick(operation, dead_);
    if (!node) throw IoError("no registered node offers " + operation + " (or every one failed)");
    protocol::HttpOptions http;
    http.timeout = std::chrono::minutes(2);
    http.bearer_token = options_.token;
    if (options_.load) options_.load(*node, +1);
    protocol::HttpResult res = protocol::http_request("POST", *node + "/run/" + operation, body, http);
    // A long run answers 202 with a task to poll.
    auto deadline = Clock::now() + kStepTimeout;
    while (res.status == 202) {
      json accepted = json::parse(res.body, nullptr, false);
      std::string task = accepted.is_object() ? accepted.value("task", "") : "";
      if (task.empty()) break;
      std::this_thread::sleep_for(std::chrono::milliseconds(200));
      protocol::HttpResult poll = protocol::http_request("GET", task, {}, http);
      if (!poll.ok()) {
        res = poll;
        break;
      }
      json state = json::parse(poll.body, nullptr, false);
      std::string s = state.value("state", "");
      if (s == "done") res = {200, state["result"].dump(), ""};
      else if (s == "failed" || s == "cancelled") res = {500, state.value("error", json()).dump(), ""};
      if (Clock::now() > deadline) res = {0, "", "step timed out"};
    }
    if (options_.load) options_.load(*node, -1);
    if (res.ok()) {
      json answer = json::parse(res.body, nullptr, false);
      if (!answer.is_object()) throw IoError(*node + " answered /run/" + operation + " with no JSON");
      return {*node, answer};
    }
    if (res.status >= 400 && res.status < 500)  // the request itself is wrong: no other node helps
      throw InvalidInput(operation + " on " + *node + ": " + res.describe());
    // Connection refused, reset, or a server error: try another node offering the operation.
    dead_.push_back(*node);
  }
}

std::int64_t HttpNodeClient::forward(const std::string& from_node, const std::string& base_sha,
                                     const Answer& answer, StepReport& report) {
  auto start = Clock::now();
  std::string output = answer.body.value("output", "");
  std::string correction = answer.body.value("correction", "");
  std::string sha = answer.body.value("sha256", "");
  bool send_correction = report.correction_bytes > 0 && report.correction_bytes < report.output_bytes;
  report.sent = send_correction ? "correction" : "output";
  protocol::HttpOptions http;
  http.timeout = std::chrono::seconds(30);
  http.bearer_token = options_.token;
  std::vector<std::string> told;
  for (const auto& node : options_.nodes) {
    if (node == from_node || std::find(dead_.begin(), dead_.end(), node) != dead_.end()) continue;
    json body = send_correction
                    ? json{{"base", base_sha}, {"correction", correction}, {"result", output}, {"result_sha256", sha}}
                    : json{{"url", output}, {"sha256", sha}};
    if (protocol::http_request("POST", node + (send_correction ? "/update" : "/download"), body.dump(), http).ok())
      told.push_back(node);
  }
  // The next step starts once every node has the result (thesis §4.2): wait and collect how
  // long each took to apply it.
  std::int64_t slowest = 0;
  for (const auto& node : told) {
    auto deadline = Clock::now() + kUpdateTimeout;
    while (Clock::now() < deadline) {
      protocol::HttpResult res = protocol::http_request("GET", node + "/cache/" + sha, {}, http);
      json state = json::parse(res.body, nullptr, false);
      std::string s = state.is_object() ? state.value("state", "") : "";
      if (s == "ready" || s == "failed" || res.status == 0) {
        if (s == "ready") slowest = std::max<std::int64_t>(slowest, state.value("ms", 0));
        break;
      }
      std::this_thread::sleep_for(kPollEvery);
    }
  }
  report.update_ms = slowest;
  return ms_since(start);
}

StepReport HttpNodeClient::run_atomic(const std::string& operation, const services::Params& params) {
  json p = json::object();
  for (const auto& [k, v] : params) p[k] = v;
  std::string body = json{{"input", current_url_}, {"sha256", current_sha_}, {"params", p},
                          {"reference_diagonal", options_.reference_diagonal}}.dump();
  Answer answer = run_on_some_node(operation, body);
  StepReport report;
  report.operation = operation;
  report.node = answer.node;
  report.run_ms = answer.body.value("run_ms", std::int64_t{0});
  report.output_bytes = answer.body.value("output_bytes", std::uint64_t{0});
  report.correction_bytes = answer.body.value("correction_bytes", std::uint64_t{0});
  std::string base = current_sha_;
  report.transfer_ms = forward(answer.node, base, answer, report);
  current_url_ = answer.body.value("output", "");
  current_sha_ = answer.body.value("sha256", "");
  return report;
}

StepReport HttpNodeClient::run_analysis(const std::string& operation) {
  std::string body = json{{"input", current_url_}, {"sha256", current_sha_}}.dump();
  Answer answer = run_on_some_node(operation, body);
  StepReport report;
  report.operation = operation;
  report.node = answer.node;
  report.is_analysis = true;
  report.value = answer.body.value("value", 0.0);
  report.run_ms = answer.body.value("run_ms", std::int64_t{0});
  return report;
}

}  // namespace meshflow::engine
