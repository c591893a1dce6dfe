#include "engine/http_node_client.h"

#include <algorithm>
#include <cctype>
#include <chrono>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <thread>

#include "mesh/canonical_copy.h"
#include "mesh/errors.h"
#include "mesh/mesh_io.h"
#include "parallel/distributed_simplify.h"
#include "parallel/node_dispatch.h"
#include "protocol/http_client.h"

namespace meshflow::engine {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr auto kStepTimeout = std::chrono::hours(2);
constexpr auto kUpdateTimeout = std::chrono::minutes(30);
constexpr auto kCallTimeout = std::chrono::minutes(2);     // one /run answer (or its 202)
constexpr auto kNoticeTimeout = std::chrono::seconds(30);  // one-way /download, /update
// Polls start fast (loopback answers in a millisecond) and back off to this.
constexpr auto kFirstPoll = std::chrono::milliseconds(1);
constexpr auto kSlowestPoll = std::chrono::milliseconds(50);
constexpr auto kSlowestTaskPoll = std::chrono::milliseconds(500);

class Backoff {
 public:
  explicit Backoff(std::chrono::milliseconds slowest) : slowest_(slowest) {}
  void wait() {
    std::this_thread::sleep_for(next_);
    next_ = std::min(next_ * 2, slowest_);
  }

 private:
  std::chrono::milliseconds next_ = kFirstPoll;
  std::chrono::milliseconds slowest_;
};

std::string url_encode(const std::string& text) {
  static const char* hex = "0123456789ABCDEF";
  std::string out;
  for (unsigned char c : text) {
    if (std::isalnum(c) || c == '-' || c == '_' || c == '.' || c == '~') {
      out += static_cast<char>(c);
    } else {
      out += '%';
      out += hex[c >> 4];
      out += hex[c & 15];
    }
  }
  return out;
}

// A node's cache entry for the mesh `sha` fetched from `url`, once it is no longer pending
// (or the deadline passes).
json settled_cache_entry(const std::string& node, const std::string& sha, const std::string& url,
                         const protocol::HttpOptions& http, Clock::duration limit,
                         const std::function<bool()>& cancelled) {
  auto deadline = Clock::now() + limit;
  Backoff backoff(kSlowestPoll);
  std::string query = node + "/cache/" + sha + "?url=" + url_encode(url);
  for (;;) {
    protocol::HttpResult res = protocol::http_request("GET", query, {}, http);
    if (res.status == 0) return json{{"state", "failed"}, {"error", res.describe()}};
    json state = json::parse(res.body, nullptr, false);
    if (!state.is_object()) state = json{{"state", "failed"}, {"error", res.describe()}};
    if (state.value("state", "") != "pending") return state;
    if (Clock::now() > deadline) return json{{"state", "failed"}, {"error", "timed out"}};
    if (cancelled && cancelled()) throw std::runtime_error("cancelled");
    backoff.wait();
  }
}

}  // namespace

const char* to_string(TransferMode mode) { return mode == TransferMode::Output ? "output" : "smaller"; }

TransferMode transfer_mode_from_string(const std::string& text) {
  if (text.empty() || text == "smaller") return TransferMode::Smaller;
  if (text == "output") return TransferMode::Output;
  throw InvalidInput("transfer must be 'smaller' (the correction or the output, whichever is smaller) or "
                     "'output' (always the whole output), not '" + text + "'");
}

struct HttpNodeClient::Answer {
  std::string node;
  json body;
};

HttpNodeClient::HttpNodeClient(HttpNodeOptions options, std::string input_url, std::string input_sha256)
    : options_(std::move(options)), input_url_(input_url), input_sha_(input_sha256),
      current_url_(std::move(input_url)), current_sha_(std::move(input_sha256)),
      current_vertices_(options_.input_vertices) {}

HttpNodeClient::~HttpNodeClient() {
  stop_broadcast_ = true;  // a job that ends early does not wait for the last downloads
  if (broadcaster_.joinable()) broadcaster_.join();
}

bool HttpNodeClient::is_dead(const std::string& node) const {
  return std::find(dead_.begin(), dead_.end(), node) != dead_.end();
}

std::string HttpNodeClient::place(const std::string& operation) {
  std::vector<NodeCandidate> candidates;
  for (NodeCandidate c : options_.candidates(operation)) {
    if (is_dead(c.url)) continue;
    for (const auto& [op, node] : plan_)
      if (node == c.url) ++c.planned_steps;
    candidates.push_back(std::move(c));
  }
  std::optional<std::string> node = choose_node(candidates);
  if (!node) throw IoError("no registered node offers " + operation + (dead_.empty() ? "" : " (or every one failed)"));
  plan_[operation] = *node;
  return *node;
}

void HttpNodeClient::plan(const std::vector<std::string>& operations) {
  for (const auto& op : operations)
    if (!plan_.count(op)) place(op);
}

std::vector<std::string> HttpNodeClient::nodes_taking_part() const {
  std::vector<std::string> nodes;
  for (const auto& [op, node] : plan_)
    if (!is_dead(node) && std::find(nodes.begin(), nodes.end(), node) == nodes.end()) nodes.push_back(node);
  return nodes;
}

void HttpNodeClient::broadcast() {
  std::vector<std::string> targets = nodes_taking_part();  // in order of first use
  {
    std::lock_guard lock(broadcast_mutex_);
    to_tell_ = targets;
  }
  broadcaster_ = std::thread([this, targets] { run_broadcast(targets); });
}

void HttpNodeClient::run_broadcast(std::vector<std::string> targets) {
  auto start = Clock::now();
  auto stop = [this] { return stop_broadcast_.load() || (options_.cancelled && options_.cancelled()); };
  protocol::HttpOptions http;
  http.timeout = kNoticeTimeout;
  http.bearer_token = options_.token;
  auto told = [&](const std::string& node) {
    std::lock_guard lock(broadcast_mutex_);
    std::erase(to_tell_, node);
    broadcast_changed_.notify_all();
  };
  try {
    std::vector<std::string> sources{input_url_};  // URLs the input can be fetched from
    std::size_t next = 0;
    while (next < targets.size()) {
      std::vector<std::pair<std::string, std::string>> round;  // node, where it fetches from
      for (const auto& source : sources) {
        if (next == targets.size()) break;
        round.emplace_back(targets[next++], source);
      }
      for (const auto& [node, url] : round) {
        protocol::http_request("POST", node + "/download", json{{"url", url}, {"sha256", input_sha_}}.dump(), http);
        told(node);
      }
      for (const auto& [node, url] : round) {
        json entry = settled_cache_entry(node, input_sha_, url, http, std::chrono::minutes(30), stop);
        if (entry.value("state", "") == "ready") {
          sources.push_back(node + "/files/" + input_sha_ + ".ply.zst");
          std::uint64_t bytes = entry.value("bytes", std::uint64_t{0});
          broadcast_.bytes = std::max(broadcast_.bytes, bytes);
          broadcast_.nodes.push_back(node);
          if (options_.measured && bytes > 0 && entry.value("how", "") == "download")
            options_.measured(node, bytes, entry.value("fetch_ms", std::int64_t{0}));
        } else if (url != input_url_) {
          // The node it fetched from failed it: straight from the hub then (its /run would too).
          protocol::http_request("POST", node + "/download", json{{"url", input_url_}, {"sha256", input_sha_}}.dump(),
                                 http);
        }
      }
    }
  } catch (...) {
    // Cancelled: nodes left out fetch their input themselves when a step needs it.
  }
  {
    std::lock_guard lock(broadcast_mutex_);
    to_tell_.clear();
    broadcast_changed_.notify_all();
  }
  broadcast_.ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start).count();
}

void HttpNodeClient::wait_until_told(const std::string& node) {
  std::unique_lock lock(broadcast_mutex_);
  broadcast_changed_.wait(lock, [&] { return std::find(to_tell_.begin(), to_tell_.end(), node) == to_tell_.end(); });
}

BroadcastReport HttpNodeClient::broadcast_report() {
  if (broadcaster_.joinable()) broadcaster_.join();
  return broadcast_;
}

HttpNodeClient::Answer HttpNodeClient::run_on_some_node(const std::string& operation, const std::string& body) {
  for (;;) {
    if (options_.cancelled && options_.cancelled()) throw std::runtime_error("cancelled");
    auto planned = plan_.find(operation);
    std::string node = planned != plan_.end() && !is_dead(planned->second) ? planned->second : place(operation);
    protocol::HttpOptions http;
    http.timeout = kCallTimeout;
    http.bearer_token = options_.token;
    wait_until_told(node);  // else it would fetch the input itself, beside the broadcast
    if (options_.on_start) options_.on_start(operation, node);
    if (options_.load) options_.load(node, +1);
    struct Unload {
      const HttpNodeOptions& o;
      const std::string& n;
      ~Unload() {
        if (o.load) o.load(n, -1);
      }
    } unload{options_, node};
    protocol::HttpResult res = protocol::http_request("POST", node + "/run/" + operation, body, http);
    // A long run answers 202 with a task to poll (DESIGN §4).
    if (res.status == 202) {
      json accepted = json::parse(res.body, nullptr, false);
      std::string task = accepted.is_object() ? accepted.value("task", "") : "";
      if (task.empty()) throw IoError(node + " answered /run/" + operation + " with 202 but no task URL");
      auto deadline = Clock::now() + kStepTimeout;
      Backoff backoff(kSlowestTaskPoll);
      for (;;) {
        if (options_.cancelled && options_.cancelled()) {
          protocol::http_request("DELETE", task, {}, http);  // the node stops the run if it can
          throw std::runtime_error("cancelled");
        }
        backoff.wait();
        protocol::HttpResult poll = protocol::http_request("GET", task, {}, http);
        if (!poll.ok()) {
          res = poll;
          break;
        }
        json state = json::parse(poll.body, nullptr, false);
        std::string s = state.is_object() ? state.value("state", "") : "";
        if (s == "done") {
          res = {200, state["result"].dump(), ""};
          break;
        }
        if (s == "failed" || s == "cancelled") {
          int status = state.value("status", 500);
          res = {status, state.contains("error") ? state["error"].dump() : "", ""};
          break;
        }
        if (Clock::now() > deadline) {
          res = {0, "", "the task " + task + " did not finish in time"};
          break;
        }
      }
    }
    if (res.ok()) {
      json answer = json::parse(res.body, nullptr, false);
      if (!answer.is_object()) throw IoError(node + " answered /run/" + operation + " with no JSON");
      return {node, answer};
    }
    // The request itself is wrong: no other node helps. (404: the node does not offer the
    // operation, or lost the task in a restart: another node may.)
    if (res.status >= 400 && res.status < 500 && res.status != 404)
      throw InvalidInput(operation + " on " + node + ": " + res.describe());
    // Connection refused or reset, a server error, a lost task: this node is out of the job,
    // its operations move elsewhere and the step runs again.
    dead_.push_back(node);
    for (auto& [op, where] : plan_)
      if (where == node) {
        std::vector<NodeCandidate> any = options_.candidates(op);
        bool other = std::any_of(any.begin(), any.end(), [&](const NodeCandidate& c) { return !is_dead(c.url); });
        if (other) place(op);
      }
  }
}

void HttpNodeClient::forward(const std::string& from_node, const std::string& base_sha, const Answer& answer,
                             StepReport& report) {
  std::vector<std::string> targets;
  for (const auto& op : later_) {
    auto it = plan_.find(op);
    if (it == plan_.end()) continue;
    const std::string& node = it->second;
    if (node == from_node || is_dead(node) || std::find(targets.begin(), targets.end(), node) != targets.end())
      continue;
    targets.push_back(node);
  }
  if (targets.empty()) return;
  std::string output = answer.body.value("output", "");
  std::string correction = answer.body.value("correction", "");
  std::string sha = answer.body.value("sha256", "");
  if (sha == base_sha) return;  // the step changed nothing: later nodes have (or are fetching) it
  bool send_correction = options_.transfer == TransferMode::Smaller && report.correction_bytes > 0 &&
                         report.correction_bytes < report.output_bytes;
  report.sent = send_correction ? "correction" : "output";
  protocol::HttpOptions http;
  http.timeout = kNoticeTimeout;
  http.bearer_token = options_.token;
  json body = send_correction
                  ? json{{"base", base_sha}, {"correction", correction}, {"result", output}, {"result_sha256", sha}}
                  : json{{"url", output}, {"sha256", sha}};
  std::vector<std::string> told;
  for (const auto& node : targets) wait_until_told(node);  // an update needs its base coming
  for (const auto& node : targets)
    if (protocol::http_request("POST", node + (send_correction ? "/update" : "/download"), body.dump(), http).ok())
      told.push_back(node);
  // The next step starts once every later node has the result (thesis §4.2).
  for (const auto& node : told) {
    json entry = settled_cache_entry(node, sha, output, http, kUpdateTimeout, options_.cancelled);
    if (entry.value("state", "") != "ready") continue;  // its /run will fetch the output itself
    std::int64_t fetch_ms = entry.value("fetch_ms", std::int64_t{0});
    std::uint64_t bytes = entry.value("bytes", std::uint64_t{0});
    report.transfer_ms = std::max(report.transfer_ms, fetch_ms);
    report.update_ms = std::max(report.update_ms, entry.value("apply_ms", std::int64_t{0}));
    if (options_.measured && bytes > 0) options_.measured(node, bytes, fetch_ms);
  }
}

std::vector<NodeCandidate> HttpNodeClient::nodes_too_small_for(const std::string& operation) const {
  if (operation != "Simplify" || current_vertices_ == 0 || !options_.publish || options_.work_dir.empty() ||
      !options_.candidates)
    return {};
  std::vector<NodeCandidate> nodes;
  for (const NodeCandidate& c : options_.candidates(operation)) {
    if (is_dead(c.url)) continue;
    if (c.capacity_vertices == 0 || c.capacity_vertices >= current_vertices_) return {};  // one takes it whole
    nodes.push_back(c);
  }
  return nodes;
}

StepReport HttpNodeClient::run_split(const std::vector<NodeCandidate>& nodes, const services::Params& params) {
  auto started = Clock::now();
  const services::OperationSpec& spec = services::find_operation("Simplify");
  auto given = [&](const std::string& name) {
    if (auto it = params.find(name); it != params.end()) return it->second;
    for (const auto& p : spec.params)
      if (p.name == name) return p.default_value;
    return 0.0;
  };
  if (given("targetVertices") > 0)
    throw InvalidInput("Simplify: a mesh larger than every node takes (" + std::to_string(current_vertices_) +
                       " vertices) is simplified in parts, which stop at maxError, not at targetVertices");
  if (!(options_.reference_diagonal > 0)) throw InvalidInput("Simplify in parts needs the input's diagonal");
  std::string label = "parts on " + std::to_string(nodes.size()) + " nodes";
  if (options_.on_start) options_.on_start("Simplify", label);
  namespace fs = std::filesystem;
  fs::path dir = fs::path(options_.work_dir) / ("split-" + std::to_string(++splits_));
  fs::remove_all(dir);
  fs::create_directories(dir / "parts");
  const std::string in = (dir / "input.ply").string(), out = (dir / "output.ply").string();
  protocol::HttpOptions http;
  http.timeout = std::chrono::minutes(30);
  protocol::DownloadResult got = protocol::http_download(current_url_, in, current_sha_, true, http);
  if (!got.ok()) throw IoError("fetching the mesh to split from " + current_url_ + ": " + got.describe());

  parallel::DistributedParams split;
  split.max_error_abs = given("maxError") / 100.0 * options_.reference_diagonal;
  split.parts_dir = (dir / "parts").string();
  // Parts well inside the smallest node (the partition's sizes are estimates from a sample).
  std::uint64_t smallest = nodes.front().capacity_vertices;
  std::vector<std::string> urls;
  for (const NodeCandidate& c : nodes) {
    smallest = std::min(smallest, c.capacity_vertices);
    urls.push_back(c.url);
  }
  split.vertices_per_part = std::max<std::uint64_t>(smallest / 2, 1000);
  parallel::NodeDispatch dispatch(urls, split.parts_dir, options_.token);
  split.workers = static_cast<unsigned>(dispatch.nodes());
  split.runner = [this, &dispatch](std::size_t p, double max_error_abs, bool fixed_seams) {
    if (options_.cancelled && options_.cancelled()) throw std::runtime_error("cancelled");
    return dispatch.run(p, max_error_abs, fixed_seams);
  };
  // A cancelled job stops at the next progress report (the parts under way on nodes finish there).
  split.progress = [this](const std::string& step, double fraction) {
    if (options_.cancelled && options_.cancelled()) throw std::runtime_error("cancelled");
    if (options_.progress) options_.progress(step, fraction);
  };
  parallel::DistributedReport done;
  try {
    done = parallel::simplify_distributed(in, out, split);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(dir, ignored);  // the input copy, the parts and their scratch
    throw;
  }
  fs::remove(in);
  fs::remove_all(dir / "parts");

  // Served like a node's outputs: canonical PLY, zstd (the SHA-256 is of the PLY), compressed
  // by a streaming copy so that the hub never holds the merged mesh.
  const std::string served = out + ".zst";
  mesh::CanonicalCopy result = mesh::copy_canonical_ply(out, served);
  fs::remove(out);
  Answer answer{"", json{{"output", options_.publish(served)}, {"sha256", result.sha256}}};
  StepReport report;
  report.operation = "Simplify";
  report.node = label + " (" + std::to_string(done.partition.parts) + " parts)";
  report.run_ms = std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - started).count();
  report.output_bytes = fs::file_size(served);
  forward("", current_sha_, answer, report);  // every later node fetches the whole output
  current_url_ = answer.body["output"];
  current_sha_ = answer.body["sha256"];
  current_node_.clear();
  report.vertices = current_vertices_ = result.vertices;
  return report;
}

StepReport HttpNodeClient::run_atomic(const std::string& operation, const services::Params& params) {
  if (std::vector<NodeCandidate> nodes = nodes_too_small_for(operation); !nodes.empty())
    return run_split(nodes, params);
  json p = json::object();
  for (const auto& [k, v] : params) p[k] = v;
  std::string body = json{{"input", current_url_}, {"sha256", current_sha_}, {"params", p},
                          {"reference_diagonal", options_.reference_diagonal}}.dump();
  Answer answer = run_on_some_node(operation, body);
  StepReport report;
  report.operation = operation;
  report.node = answer.node;
  report.run_ms = answer.body.value("run_ms", std::int64_t{0});
  report.wait_ms = answer.body.value("wait_ms", std::int64_t{0});
  report.output_bytes = answer.body.value("output_bytes", std::uint64_t{0});
  report.correction_bytes = answer.body.value("correction_bytes", std::uint64_t{0});
  std::string base = current_sha_;
  forward(answer.node, base, answer, report);
  current_url_ = answer.body.value("output", "");
  current_sha_ = answer.body.value("sha256", "");
  current_node_ = answer.node;
  current_vertices_ = 0;
  if (auto stats = answer.body.find("stats"); stats != answer.body.end() && stats->is_object())
    current_vertices_ = stats->value("NumberOfVertices", std::uint64_t{0});
  report.vertices = current_vertices_;
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
  report.wait_ms = answer.body.value("wait_ms", std::int64_t{0});
  return report;
}

}  // namespace meshflow::engine
