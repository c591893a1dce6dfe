#include "parallel/node_dispatch.h"

#include <httplib.h>
#include <unistd.h>

#include <algorithm>
#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "mesh/errors.h"
#include "mesh/part_files.h"
#include "parallel/distributed_simplify.h"
#include "parallel/partition.h"
#include "protocol/http_client.h"
#include "protocol/http_server.h"

namespace meshflow::parallel {
namespace {

using nlohmann::json;

bool is_loopback(const std::string& url) {
  std::string origin = protocol::url_origin(url);
  return origin.find("://127.") != std::string::npos || origin.find("://localhost") != std::string::npos ||
         origin.find("://[::1]") != std::string::npos;
}

}  // namespace

struct NodeDispatch::Impl {
  std::vector<std::string> nodes;
  enum State { kFree, kBusy, kDown };
  std::vector<State> state;
  std::string last_failure;
  std::mutex mutex;
  std::condition_variable freed;
  std::string dir, base_url, token;
  httplib::Server server;
  std::thread thread;
};

NodeDispatch::NodeDispatch(std::vector<std::string> node_urls, std::string parts_dir, std::string token)
    : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
  d.token = std::move(token);
  if (node_urls.empty()) throw InvalidInput("--nodes: give at least one node URL");
  bool loopback = true;
  for (auto& url : node_urls) {
    while (!url.empty() && url.back() == '/') url.pop_back();
    if (protocol::url_origin(url).empty()) throw InvalidInput("--nodes: not an http URL: " + url);
    protocol::HttpOptions http;
    http.timeout = std::chrono::seconds(10);
    protocol::HttpResult r = protocol::http_request("GET", url + "/service.json", {}, http);
    json body = r.ok() ? json::parse(r.body, nullptr, false) : json();
    if (!r.ok() || !body.is_object())
      throw InvalidInput("--nodes: " + url + " is not a reachable mesh node (" + (r.ok() ? "no JSON" : r.describe()) + ")");
    loopback = loopback && is_loopback(url);
  }
  d.nodes = std::move(node_urls);
  d.state.assign(d.nodes.size(), Impl::kFree);
  d.dir = std::move(parts_dir);
  protocol::install_error_handling(d.server);
  d.server.Get(R"(/parts/(part-\d+\.mfp|seam-\d+-\d+\.mfp|rem-\d+-\d+\.bin))", [&d](const httplib::Request& req, httplib::Response& res) {
    const std::string name = req.matches[1], path = d.dir + "/" + name;
    // A seam with no vertex shared by the two parts alone has no file: an empty side.
    if (name.rfind("seam-", 0) == 0 && !std::filesystem::exists(path)) {
      const std::vector<std::uint8_t> empty = mesh::encode_part({});
      res.set_content(std::string(empty.begin(), empty.end()), "application/octet-stream");
      return;
    }
    protocol::serve_file(req, res, path, "application/octet-stream");
  });
  const std::string host = loopback ? "127.0.0.1" : "0.0.0.0";
  int port = d.server.bind_to_any_port(host);
  if (port <= 0) throw IoError("cannot serve the part files on " + host);
  char name[256] = "127.0.0.1";
  if (!loopback) gethostname(name, sizeof name - 1);
  d.base_url = "http://" + std::string(name) + ":" + std::to_string(port);
  d.thread = std::thread([&d] { d.server.listen_after_bind(); });
}

NodeDispatch::~NodeDispatch() {
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::size_t NodeDispatch::nodes() const { return impl_->nodes.size(); }

namespace {

// One attempt on a node. \throws NodeDown when no answer came (the part may go to another node).
struct NodeDown : std::runtime_error {
  using std::runtime_error::runtime_error;
};

services::PartStats run_on(const std::string& node, const std::string& base_url, const std::string& dir, std::size_t p,
                           double max_error_abs, bool fixed_seams, const std::string& token) {
  const std::string part_url = base_url + "/parts/part-" + std::to_string(p) + ".mfp";
  json request{{"vertices", part_url}, {"triangles", part_url}, {"boundary", part_url}, {"removed", json::array()},
               {"max_error_abs", max_error_abs}};
  std::vector<std::uint32_t> unprocessed;
  if (!fixed_seams) {
    // As simplify_one_part: a neighbour with a Rem file for p is done, the others come later.
    request["part"] = p;
    request["unprocessed"] = json::array();
    const PartitionInfo info = read_partition_info(dir);
    for (std::uint32_t q : info.adjacency.at(p)) {
      if (std::filesystem::exists(rem_path(dir, q, p))) {
        request["removed"].push_back({{"from_part", q}, {"url", base_url + "/parts/rem-" + std::to_string(q) + "-" + std::to_string(p) + ".bin"}});
      } else {
        unprocessed.push_back(q);
        request["unprocessed"].push_back({{"part", q}, {"url", base_url + "/parts/seam-" + std::to_string(q) + "-" + std::to_string(p) + ".mfp"}});
      }
    }
  }
  protocol::HttpOptions http;
  http.timeout = std::chrono::minutes(60);
  http.bearer_token = token;
  protocol::HttpResult r = protocol::http_request("POST", node + "/parts/simplify", request.dump(), http);
  if (r.status == 0) throw NodeDown(node + ": " + r.describe());
  json answer = json::parse(r.body, nullptr, false);
  while (r.status == 202 && answer.is_object() && answer.contains("task") && answer["task"].is_string()) {  // poll the task
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    protocol::HttpResult t = protocol::http_request("GET", answer["task"].get<std::string>(), {}, http);
    if (t.status == 0) throw NodeDown(node + ": " + t.describe());
    json state = json::parse(t.body, nullptr, false);
    if (!t.ok() || !state.is_object()) throw IoError(node + ": lost the task of part " + std::to_string(p) + ": " + t.describe());
    if (state.value("state", "") == "running") continue;
    if (state.value("state", "") != "done") throw IoError(node + ": part " + std::to_string(p) + " failed: " + state.dump());
    r.status = 200;
    answer = state["result"];
  }
  if (!r.ok() || !answer.is_object() || !answer.contains("part") || !answer["part"].is_string())
    throw IoError(node + ": part " + std::to_string(p) + ": " + r.describe());
  // Each Rem file first: the simplified part's presence means the part is complete.
  const json& removed = answer.contains("removed") ? answer["removed"] : json();
  if (!fixed_seams && (!removed.is_array() || removed.size() != unprocessed.size()))
    throw IoError(node + ": part " + std::to_string(p) + ": one Rem file per unprocessed neighbour expected, got " + removed.dump());
  for (std::size_t i = 0; !fixed_seams && i < unprocessed.size(); ++i) {
    const json& rem = removed[i];
    if (!rem.is_object() || rem.value("to_part", json()) != json(unprocessed[i]) || !rem.contains("url") || !rem["url"].is_string())
      throw IoError(node + ": part " + std::to_string(p) + ": expected the Rem file for part " + std::to_string(unprocessed[i]) +
                    ", got " + rem.dump());
    std::optional<std::string> rem_sha;
    if (rem.contains("sha256") && rem["sha256"].is_string()) rem_sha = rem["sha256"].get<std::string>();
    const std::string path = rem_path(dir, p, unprocessed[i]);
    protocol::DownloadResult got = protocol::http_download(rem["url"].get<std::string>(), path + ".tmp", rem_sha);
    if (got.status == 0 && got.error.find("SHA") == std::string::npos) throw NodeDown(node + ": " + got.describe());
    if (!got.ok()) throw IoError(node + ": cannot fetch the Rem file " + std::to_string(p) + " -> " + std::to_string(unprocessed[i]) + ": " + got.describe());
    mesh::read_rem(path + ".tmp");  // refused here, naming the byte, rather than by the next part
    std::filesystem::rename(path + ".tmp", path);
  }
  std::optional<std::string> sha;
  if (answer.contains("sha256") && answer["sha256"].is_string()) sha = answer["sha256"].get<std::string>();
  protocol::DownloadResult got = protocol::http_download(answer["part"].get<std::string>(), part_path(dir, p, true), sha);
  if (got.status == 0 && got.error.find("SHA") == std::string::npos) throw NodeDown(node + ": " + got.describe());
  if (!got.ok()) throw IoError(node + ": cannot fetch the simplified part " + std::to_string(p) + ": " + got.describe());
  return stats_from_json(answer.value("stats", json::object()));
}

}  // namespace

// A node that does not answer is dropped and the part goes to another (DESIGN §10).
services::PartStats NodeDispatch::run(std::size_t p, double max_error_abs, bool fixed_seams) {
  Impl& d = *impl_;
  for (;;) {
    std::size_t n;
    {
      std::unique_lock lock(d.mutex);
      auto usable = [&] { return std::find(d.state.begin(), d.state.end(), Impl::kFree) != d.state.end(); };
      auto alive = [&] { return std::count(d.state.begin(), d.state.end(), Impl::kDown) < static_cast<long>(d.state.size()); };
      d.freed.wait(lock, [&] { return usable() || !alive(); });
      if (!alive()) throw IoError("every node stopped answering: " + d.last_failure);
      n = std::find(d.state.begin(), d.state.end(), Impl::kFree) - d.state.begin();
      d.state[n] = Impl::kBusy;
    }
    try {
      services::PartStats stats = run_on(d.nodes[n], d.base_url, d.dir, p, max_error_abs, fixed_seams, d.token);
      std::lock_guard lock(d.mutex);
      d.state[n] = Impl::kFree;
      d.freed.notify_one();
      return stats;
    } catch (const NodeDown& e) {
      std::lock_guard lock(d.mutex);
      d.state[n] = Impl::kDown;
      d.last_failure = e.what();
      d.freed.notify_all();
    } catch (...) {
      std::lock_guard lock(d.mutex);
      d.state[n] = Impl::kFree;
      d.freed.notify_one();
      throw;
    }
  }
}

}  // namespace meshflow::parallel
