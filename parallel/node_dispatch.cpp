#include "parallel/node_dispatch.h"

#include <httplib.h>
#include <unistd.h>

#include <condition_variable>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <thread>

#include "mesh/errors.h"
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
  std::vector<bool> busy;
  std::mutex mutex;
  std::condition_variable freed;
  std::string dir, base_url;
  httplib::Server server;
  std::thread thread;
};

NodeDispatch::NodeDispatch(std::vector<std::string> node_urls, std::string parts_dir) : impl_(std::make_unique<Impl>()) {
  Impl& d = *impl_;
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
  d.busy.assign(d.nodes.size(), false);
  d.dir = std::move(parts_dir);
  d.server.Get(R"(/parts/(part-\d+\.mfp))", [&d](const httplib::Request& req, httplib::Response& res) {
    protocol::serve_file(req, res, d.dir + "/" + std::string(req.matches[1]), "application/octet-stream");
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

services::PartStats NodeDispatch::run(std::size_t p, double max_error_abs) {
  Impl& d = *impl_;
  std::size_t n;
  {
    std::unique_lock lock(d.mutex);
    d.freed.wait(lock, [&] { return std::find(d.busy.begin(), d.busy.end(), false) != d.busy.end(); });
    n = std::find(d.busy.begin(), d.busy.end(), false) - d.busy.begin();
    d.busy[n] = true;
  }
  struct Release {
    Impl& d;
    std::size_t n;
    ~Release() {
      std::lock_guard lock(d.mutex);
      d.busy[n] = false;
      d.freed.notify_one();
    }
  } release{d, n};
  const std::string node = d.nodes[n];
  const std::string part_url = d.base_url + "/parts/part-" + std::to_string(p) + ".mfp";
  json request{{"vertices", part_url}, {"triangles", part_url}, {"removed", json::array()}, {"max_error_abs", max_error_abs}};
  protocol::HttpOptions http;
  http.timeout = std::chrono::minutes(60);
  protocol::HttpResult r = protocol::http_request("POST", node + "/parts/simplify", request.dump(), http);
  json answer = json::parse(r.body, nullptr, false);
  while (r.status == 202 && answer.is_object() && answer.contains("task")) {  // a long run: poll its task
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    protocol::HttpResult t = protocol::http_request("GET", answer["task"].get<std::string>(), {}, http);
    json state = json::parse(t.body, nullptr, false);
    if (!t.ok() || !state.is_object()) throw IoError(node + ": lost the task of part " + std::to_string(p) + ": " + t.describe());
    if (state.value("state", "") == "running") continue;
    if (state.value("state", "") != "done") throw IoError(node + ": part " + std::to_string(p) + " failed: " + state.dump());
    r.status = 200;
    answer = state["result"];
  }
  if (!r.ok() || !answer.is_object() || !answer.contains("part") || !answer["part"].is_string())
    throw IoError(node + ": part " + std::to_string(p) + ": " + r.describe());
  protocol::DownloadResult got =
      protocol::http_download(answer["part"].get<std::string>(), part_path(d.dir, p, true), answer.value("sha256", std::string()).empty()
                                                                                                 ? std::nullopt
                                                                                                 : std::optional<std::string>(answer["sha256"]));
  if (!got.ok()) throw IoError(node + ": cannot fetch the simplified part " + std::to_string(p) + ": " + got.describe());
  return stats_from_json(answer.value("stats", json::object()));
}

}  // namespace meshflow::parallel
