#include "services/node_server.h"

#include <httplib.h>

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <nlohmann/json.hpp>
#include <set>

#include "mesh/canonical_ply.h"
#include "mesh/errors.h"
#include "mesh/measures.h"
#include "mesh/mesh_io.h"
#include "protocol/correction.h"
#include "protocol/http_client.h"
#include "protocol/http_server.h"
#include "protocol/mesh_cache.h"
#include "services/operation.h"
#include "services/part_simplify.h"

namespace meshflow::services {
namespace {

using nlohmann::json;
using Clock = std::chrono::steady_clock;

constexpr std::chrono::minutes kInputWait{30};          // pending download/update of an input
constexpr std::size_t kMaxJsonBody = 1 << 20;
const char* kVersion = "0.1.0";

std::int64_t ms_since(Clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(Clock::now() - start).count();
}

json parse_body(const httplib::Request& req) {
  if (req.body.size() > kMaxJsonBody)
    throw LimitExceeded("request body too large", kMaxJsonBody, req.body.size());
  json body = json::parse(req.body, nullptr, false);
  if (body.is_discarded() || !body.is_object())
    throw InvalidInput("request body is not a JSON object");
  return body;
}

std::string required_string(const json& body, const char* key) {
  auto it = body.find(key);
  if (it == body.end() || !it->is_string() || it->get<std::string>().empty())
    throw InvalidInput(std::string("missing string field '") + key + "'");
  return it->get<std::string>();
}

// "http://h:p/files/<sha>.ply.zst" -> "<sha>", else "".
std::string sha_from_url(const std::string& url) {
  auto slash = url.find_last_of('/');
  std::string name = slash == std::string::npos ? url : url.substr(slash + 1);
  auto dot = name.find('.');
  std::string stem = name.substr(0, dot);
  if (stem.size() == 64 && stem.find_first_not_of("0123456789abcdef") == std::string::npos)
    return stem;
  return {};
}

std::map<std::string, std::string> params_from_json(const json& params) {
  std::map<std::string, std::string> out;
  if (params.is_null()) return out;
  if (!params.is_object()) throw InvalidInput("'params' must be a JSON object");
  for (const auto& [key, value] : params.items()) {
    if (value.is_string()) out[key] = value.get<std::string>();
    else if (value.is_boolean()) out[key] = value.get<bool>() ? "true" : "false";
    else if (value.is_number()) out[key] = value.dump();
    else throw InvalidInput("parameter '" + key + "' must be a number, a boolean or a string");
  }
  return out;
}

}  // namespace

struct NodeServer::Impl {
  NodeOptions options;
  httplib::Server server;
  std::thread thread;
  int port = 0;
  std::unique_ptr<protocol::MeshCache> cache;

  // Long runs as tasks (DESIGN §4).
  struct Task {
    std::string state = "running";  // running, done, failed, cancelled
    json result;
    std::string error;
    int error_status = 500;
    std::atomic<bool> cancel{false};
    Clock::time_point finished;
  };
  // A finished task's answer stays this long for its poller, then goes.
  static constexpr std::chrono::minutes kKeepFinishedTasks{10};
  std::mutex tasks_mutex;
  std::condition_variable task_done;
  std::map<std::string, std::shared_ptr<Task>> tasks;
  std::uint64_t next_task = 1;
  std::atomic<int> running{0};

  std::string url() const {
    return options.advertise_url.empty()
               ? "http://" + options.host + ":" + std::to_string(port)
               : options.advertise_url;
  }
  std::string file_url(const std::string& name) const { return url() + "/files/" + name; }

  void require_token(const httplib::Request& req) const {
    if (options.token.empty()) return;
    if (req.get_header_value("Authorization") != "Bearer " + options.token)
      throw protocol::Unauthorized("this route needs the node token");
  }

  // Origins a node may fetch from: the hub, itself, and the nodes registered with the hub
  // (asked again whenever an unknown origin shows up).
  void check_fetch_origin(const std::string& fetch_url) {
    std::string origin = protocol::url_origin(fetch_url);
    if (origin.empty()) throw InvalidInput("not an http URL: " + fetch_url);
    if (options.hub_url.empty()) return;  // standalone node (tests, `meshflow run`)
    if (allowed_origins().count(origin)) return;
    refresh_allowed_origins();
    if (!allowed_origins().count(origin))
      throw protocol::Forbidden("refusing to fetch from " + origin +
                                ": not the hub or a registered node");
  }
  // Part files (POST /parts/simplify) come from the coordinator of a split Simplify step: the
  // hub itself, serving them on a port of its own, so the hub's host at any port is allowed too.
  void check_part_origin(const std::string& part_url) {
    if (!options.hub_url.empty() &&
        host_of(protocol::url_origin(part_url)) == host_of(protocol::url_origin(options.hub_url)))
      return;
    check_fetch_origin(part_url);
  }
  // "http://h:1" -> "h", "http://[::1]:1" -> "[::1]"
  static std::string host_of(const std::string& origin) {
    auto start = origin.find("://");
    std::string host = start == std::string::npos ? origin : origin.substr(start + 3);
    auto colon = host.rfind(':');
    if (colon != std::string::npos && host.find(']', colon) == std::string::npos) host.resize(colon);
    return host;
  }
  std::mutex origins_mutex;
  std::set<std::string> origins;
  std::set<std::string> allowed_origins() {
    std::lock_guard lock(origins_mutex);
    return origins;
  }
  void refresh_allowed_origins() {
    protocol::HttpOptions http;
    http.timeout = std::chrono::seconds(10);
    http.bearer_token = options.token;
    protocol::HttpResult res = protocol::http_request("GET", options.hub_url + "/api/services", {}, http);
    std::set<std::string> fresh{protocol::url_origin(options.hub_url), protocol::url_origin(url())};
    if (res.ok()) {
      json body = json::parse(res.body, nullptr, false);
      const json& list = body.is_object() && body.contains("services") ? body["services"] : body;
      if (list.is_array())
        for (const auto& service : list)
          if (service.is_object() && service.contains("url") && service["url"].is_string())
            fresh.insert(protocol::url_origin(service["url"].get<std::string>()));
    }
    std::lock_guard lock(origins_mutex);
    origins = std::move(fresh);
  }

  bool offers(const std::string& name) const {
    return options.operations.empty() ||
           std::find(options.operations.begin(), options.operations.end(), name) != options.operations.end();
  }

  json service_json() const {
    json offered = json::array();
    for (const auto& op : operations_to_json())
      if (offers(op.value("name", ""))) offered.push_back(op);
    return {{"name", "meshflow-node"},
            {"version", kVersion},
            {"url", url()},
            {"capacity_vertices", options.capacity_vertices},
            {"operations", offered}};
  }

  // Runs one operation on the mesh named by `input` (URL or SHA-256). Atomic operations store
  // the output and the correction under /files; analysis operations give a value.
  json run_operation(const std::string& name, const json& body, const std::atomic<bool>& cancel) {
    const OperationSpec& spec = find_operation(name);
    Params params = resolve_params(spec, params_from_json(body.value("params", json())));
    std::string input = required_string(body, "input");
    std::optional<std::string> input_sha;
    if (body.contains("sha256") && body["sha256"].is_string()) input_sha = body["sha256"].get<std::string>();
    else if (auto from_url = sha_from_url(input); !from_url.empty()) input_sha = from_url;
    // The mesh may already be here under its hash (our own output, or a pending update).
    std::string key = input;
    if (input_sha && cache->find(*input_sha)) {
      key = *input_sha;
    } else if (input.find("://") != std::string::npos) {
      check_fetch_origin(input);
      if (!cache->find(input)) cache->download(input, input_sha);
    }
    protocol::MeshCache::Loaded loaded = cache->wait_mesh(key, kInputWait);
    if (loaded.mesh->num_vertices() > options.capacity_vertices)
      throw LimitExceeded("mesh larger than this node's capacity in vertices",
                          options.capacity_vertices, loaded.mesh->num_vertices());
    running++;
    struct Done {
      std::atomic<int>& n;
      ~Done() { n--; }
    } done{running};
    auto start = Clock::now();
    if (spec.kind == OperationKind::Analysis) {
      double value = run_analysis(spec, *loaded.mesh);
      return {{"value", value}, {"run_ms", ms_since(start)}, {"wait_ms", loaded.wait_ms}};
    }
    RunContext context;
    context.reference_diagonal = body.value("reference_diagonal", 0.0);
    context.cancel = &cancel;
    AtomicResult result = run_atomic(spec, *loaded.mesh, params, context);
    std::int64_t run_ms = ms_since(start);
    auto output = std::make_shared<mesh::Mesh>(std::move(result.output));
    std::string sha = cache->store(output);
    std::string correction_name = loaded.sha256 + "-" + sha + ".mfc";
    auto correction = protocol::encode_correction(*loaded.mesh, loaded.sha256, sha, result.edits);
    cache->store_file(correction_name, std::string(correction.begin(), correction.end()));
    auto output_bytes = std::filesystem::file_size(cache->mesh_path(sha));
    mesh::Measures stats = mesh::compute_measures(*output);
    return {{"output", file_url(sha + ".ply.zst")},
            {"output_bytes", output_bytes},
            {"correction", file_url(correction_name)},
            {"correction_bytes", correction.size()},
            {"sha256", sha},
            {"base_sha256", loaded.sha256},
            {"edits_streamed", result.edits_streamed},
            {"stats", json::parse(mesh::measures_to_json(stats))},
            {"run_ms", run_ms},
            {"wait_ms", loaded.wait_ms}};
  }

  // Runs `work` on its own thread; answers its result, or 202 with a task URL to poll when it
  // takes longer than options.answer_within (DESIGN §4).
  void answer_as_task(httplib::Response& res, std::function<json(const std::atomic<bool>&)> work) {
    auto task = std::make_shared<Task>();
    std::string id;
    {
      std::lock_guard lock(tasks_mutex);
      std::erase_if(tasks, [](const auto& entry) {
        return entry.second->state != "running" && Clock::now() - entry.second->finished > kKeepFinishedTasks;
      });
      id = std::to_string(next_task++);
      tasks[id] = task;
    }
    std::thread([this, task, work] {
      json result;
      std::string error;
      int status = 500;
      try {
        result = work(task->cancel);
      } catch (...) {
        protocol::ErrorReply reply = protocol::error_reply(std::current_exception());
        error = reply.body;
        status = reply.status;
      }
      std::lock_guard lock(tasks_mutex);
      if (task->cancel) task->state = "cancelled";
      else if (error.empty()) task->state = "done";
      else task->state = "failed";
      task->result = std::move(result);
      task->error = std::move(error);
      task->error_status = status;
      task->finished = Clock::now();
      task_done.notify_all();
    }).detach();
    std::unique_lock lock(tasks_mutex);
    // With answer_within 0 every run is a task, even one that has already finished.
    const bool as_task = options.answer_within.count() == 0 ||
                         !task_done.wait_for(lock, options.answer_within, [&] { return task->state != "running"; });
    if (as_task) {
      res.status = 202;
      res.set_content(json{{"task", url() + "/tasks/" + id}, {"state", task->state}}.dump(),
                      "application/json");
      return;
    }
    tasks.erase(id);
    if (task->state == "done") {
      res.set_content(task->result.dump(), "application/json");
    } else {
      res.status = task->state == "cancelled" ? 409 : task->error_status;
      res.set_content(task->error.empty() ? R"({"error":"cancelled"})" : task->error,
                      "application/json");
    }
  }

  // A part file or Rem file named by the coordinator, fetched and read whole.
  std::vector<std::uint8_t> fetch_part_bytes(const std::string& url) {
    check_part_origin(url);
    const auto incoming = cache->files_dir() / ("incoming-" + std::to_string(next_incoming++));
    protocol::DownloadResult got = protocol::http_download(url, incoming.string());
    if (!got.ok()) {
      std::error_code ignored;
      std::filesystem::remove(incoming, ignored);
      throw IoError("cannot fetch " + url + ": " + got.describe());
    }
    std::vector<std::uint8_t> bytes = mesh::read_file_bytes(incoming.string());
    std::filesystem::remove(incoming);
    return bytes;
  }

  // DESIGN §9's per-part step. With "part", the Rem scheme (services/part_simplify.h): the Rem
  // files of the simplified neighbours in "removed", the unprocessed neighbours' triangles at
  // the common vertices in "unprocessed"; one Rem file answered per unprocessed neighbour.
  // Without it, every shared vertex stays fixed and "removed" must be empty.
  json run_part(const json& body) {
    const std::string part_url = required_string(body, "vertices");
    for (const char* same : {"triangles", "boundary"})
      if (body.contains(same) && !(body[same].is_string() && body[same] == part_url))
        throw InvalidInput(std::string("'") + same + "' must name the same part file as 'vertices' (one .mfp holds all three)");
    auto e = body.find("max_error_abs");
    if (e == body.end() || !e->is_number() || !(e->get<double>() > 0))
      throw InvalidInput("'max_error_abs' must be a number > 0");
    const json removed = body.value("removed", json::array()), unprocessed = body.value("unprocessed", json::array());
    if (!removed.is_array() || !unprocessed.is_array()) throw InvalidInput("'removed' and 'unprocessed' must be arrays");
    const bool rem = body.contains("part");
    if (!rem && (!removed.empty() || !unprocessed.empty()))
      throw InvalidInput("'removed' and 'unprocessed' need 'part' (this part's number); without it shared vertices stay fixed");
    PartSeams seams;
    if (rem) {
      if (!body["part"].is_number_unsigned() || body["part"].get<std::uint64_t>() >= (1u << 24))
        throw InvalidInput("'part' must be a part number");
      seams.part = body["part"].get<std::uint32_t>();
    }
    auto part_number = [](const json& entry, const char* key, const char* list) {
      if (!entry.is_object() || !entry.contains(key) || !entry[key].is_number_unsigned() || !entry.contains("url") ||
          !entry["url"].is_string())
        throw InvalidInput(std::string("each of '") + list + "' needs \"" + key + "\" (a part number) and \"url\"");
      return entry[key].get<std::uint32_t>();
    };
    for (const json& entry : removed) {
      const std::uint32_t from = part_number(entry, "from_part", "removed");
      const std::string url = entry["url"];
      std::vector<std::uint8_t> bytes = fetch_part_bytes(url);
      mesh::RemFile file = mesh::decode_rem(bytes, url);
      if (file.from != from || file.to != seams.part)
        throw InvalidInput(url + ": a Rem file from part " + std::to_string(file.from) + " to " + std::to_string(file.to) +
                           ", expected " + std::to_string(from) + " -> " + std::to_string(seams.part));
      seams.incoming.push_back(std::move(file));
    }
    for (const json& entry : unprocessed) {
      seams.unsimplified.push_back(part_number(entry, "part", "unprocessed"));
      const std::string url = entry["url"];
      seams.unsimplified_parts.push_back(mesh::decode_part(fetch_part_bytes(url), url));
    }
    std::vector<std::uint8_t> bytes = fetch_part_bytes(part_url);
    mesh::PartFile part = mesh::decode_part(bytes, part_url);
    bytes = {};
    if (part.positions.size() > options.capacity_vertices)
      throw LimitExceeded("part larger than this node's capacity in vertices", options.capacity_vertices, part.positions.size());
    running++;
    struct Done {
      std::atomic<int>& n;
      ~Done() { n--; }
    } done{running};
    PartStats stats;
    std::vector<mesh::RemFile> outgoing;
    std::vector<std::uint8_t> out =
        mesh::encode_part(simplify_part(part, e->get<double>(), &stats, rem ? &seams : nullptr, &outgoing));
    json rem_files = json::array();
    for (const mesh::RemFile& file : outgoing) {
      std::vector<std::uint8_t> encoded = mesh::encode_rem(file);
      std::string sha = mesh::sha256_hex(encoded.data(), encoded.size());
      cache->store_file(sha + ".rem", std::string(encoded.begin(), encoded.end()));
      rem_files.push_back({{"to_part", file.to}, {"url", file_url(sha + ".rem")}, {"sha256", sha}});
    }
    std::string sha = mesh::sha256_hex(out.data(), out.size());
    cache->store_file(sha + ".mfp", std::string(out.begin(), out.end()));
    return {{"part", file_url(sha + ".mfp")}, {"sha256", sha}, {"boundary", file_url(sha + ".mfp")}, {"removed", rem_files},
            {"stats", json::parse(stats.to_json())}};
  }
  std::atomic<std::uint64_t> next_incoming{1};

  void routes() {
    protocol::install_error_handling(server);
    server.Get("/healthz", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(R"({"status":"ok"})", "application/json");
    });
    server.Get("/service.json", [this](const httplib::Request&, httplib::Response& res) {
      json body = service_json();
      body["load"] = running.load();
      res.set_content(body.dump(), "application/json");
    });
    server.Post("/download", [this](const httplib::Request& req, httplib::Response& res) {
      require_token(req);
      json body = parse_body(req);
      std::string fetch_url = required_string(body, "url");
      check_fetch_origin(fetch_url);
      std::optional<std::string> sha;
      if (body.contains("sha256") && body["sha256"].is_string()) sha = body["sha256"];
      else if (auto from_url = sha_from_url(fetch_url); !from_url.empty()) sha = from_url;
      cache->download(fetch_url, sha);
      res.status = 202;
      res.set_content(json{{"state", "pending"}, {"url", fetch_url}}.dump(), "application/json");
    });
    server.Post("/update", [this](const httplib::Request& req, httplib::Response& res) {
      require_token(req);
      json body = parse_body(req);
      std::string base = required_string(body, "base");
      std::string correction = required_string(body, "correction");
      std::string result = required_string(body, "result");
      std::string result_sha = body.value("result_sha256", sha_from_url(result));
      if (result_sha.empty()) throw InvalidInput("cannot tell the result's SHA-256: give 'result_sha256'");
      check_fetch_origin(correction);
      check_fetch_origin(result);
      if (base.find("://") != std::string::npos) {
        auto entry = cache->find(base);
        std::string base_sha = entry ? entry->sha256 : sha_from_url(base);
        if (base_sha.empty()) throw InvalidInput("base " + base + " is not in this node's cache");
        base = base_sha;
      }
      cache->update(base, correction, result, result_sha);
      res.status = 202;
      res.set_content(json{{"state", "pending"}, {"result", result}}.dump(), "application/json");
    });
    // ?url=U: the entry of that download or update (several may yield the same mesh).
    server.Get(R"(/cache/([0-9a-f]{64}))", [this](const httplib::Request& req, httplib::Response& res) {
      std::string sha = req.matches[1];
      auto entry = cache->find(req.has_param("url") ? req.get_param_value("url") : sha);
      if (entry && entry->sha256 != sha) entry.reset();
      if (!entry) throw protocol::NotFound("no cache entry for " + sha);
      json body{{"state", protocol::to_string(entry->state)}, {"ms", entry->ms}, {"how", entry->how},
                {"bytes", entry->bytes}, {"fetch_ms", entry->fetch_ms}, {"apply_ms", entry->apply_ms}};
      if (!entry->error.empty()) body["error"] = entry->error;
      res.set_content(body.dump(), "application/json");
    });
    server.Post(R"(/run/([A-Za-z]+))", [this](const httplib::Request& req, httplib::Response& res) {
      require_token(req);
      json body = parse_body(req);
      std::string name = req.matches[1];
      find_operation(name);  // unknown names: 400 before a task starts
      if (!offers(name)) throw protocol::NotFound("this node does not offer " + name);
      answer_as_task(res, [this, name, body](const std::atomic<bool>& cancel) { return run_operation(name, body, cancel); });
    });
    // DESIGN §9's per-part step (services/part_simplify.h) on a part file fetched over HTTP.
    server.Post("/parts/simplify", [this](const httplib::Request& req, httplib::Response& res) {
      require_token(req);
      json body = parse_body(req);
      answer_as_task(res, [this, body](const std::atomic<bool>&) { return run_part(body); });
    });
    server.Get(R"(/tasks/(\d+))", [this](const httplib::Request& req, httplib::Response& res) {
      std::lock_guard lock(tasks_mutex);
      auto it = tasks.find(req.matches[1]);
      if (it == tasks.end()) throw protocol::NotFound("no task " + std::string(req.matches[1]));
      const Task& task = *it->second;
      json body{{"state", task.state}};
      if (task.state == "done") body["result"] = task.result;
      if (!task.error.empty()) {
        body["error"] = json::parse(task.error, nullptr, false);
        body["status"] = task.error_status;
      }
      res.set_content(body.dump(), "application/json");
    });
    server.Delete(R"(/tasks/(\d+))", [this](const httplib::Request& req, httplib::Response& res) {
      require_token(req);
      std::lock_guard lock(tasks_mutex);
      auto it = tasks.find(req.matches[1]);
      if (it == tasks.end()) throw protocol::NotFound("no task " + std::string(req.matches[1]));
      it->second->cancel = true;
      res.status = 202;
      res.set_content(R"({"state":"cancelling"})", "application/json");
    });
    server.Get(R"(/files/([0-9a-f]{64}\.ply\.zst))", [this](const httplib::Request& req, httplib::Response& res) {
      std::string name = req.matches[1];
      protocol::serve_file(req, res, cache->mesh_path(name.substr(0, 64)).string(), "application/zstd");
    });
    server.Get(R"(/files/([0-9a-f]{64}\.(mfp|rem)))", [this](const httplib::Request& req, httplib::Response& res) {
      protocol::serve_file(req, res, (cache->files_dir() / std::string(req.matches[1])).string(),
                           "application/octet-stream");
    });
    server.Get(R"(/files/([0-9a-f]{64}-[0-9a-f]{64}\.mfc))", [this](const httplib::Request& req, httplib::Response& res) {
      protocol::serve_file(req, res, (cache->files_dir() / std::string(req.matches[1])).string(),
                           "application/octet-stream");
    });
  }
};

NodeServer::NodeServer(NodeOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
  if (impl_->options.data_dir.empty()) throw InvalidInput("a node needs a data directory");
  protocol::MeshCacheOptions cache_options;
  cache_options.dir = impl_->options.data_dir;
  impl_->cache = std::make_unique<protocol::MeshCache>(cache_options);
  int threads = impl_->options.threads;
  impl_->server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  impl_->routes();
}

NodeServer::~NodeServer() { stop(); }

int NodeServer::start() {
  Impl& d = *impl_;
  d.port = d.options.port == 0 ? d.server.bind_to_any_port(d.options.host)
                               : (d.server.bind_to_port(d.options.host, d.options.port)
                                      ? d.options.port
                                      : -1);
  if (d.port <= 0)
    throw IoError("cannot listen on " + d.options.host + ":" + std::to_string(d.options.port));
  d.thread = std::thread([&d] { d.server.listen_after_bind(); });
  return d.port;
}

void NodeServer::register_with_hub() {
  Impl& d = *impl_;
  if (d.options.hub_url.empty()) return;
  protocol::HttpOptions http;
  http.timeout = std::chrono::seconds(30);
  http.bearer_token = d.options.token;
  protocol::HttpResult res = protocol::http_request(
      "POST", d.options.hub_url + "/api/services", json{{"url", d.url()}}.dump(), http);
  if (!res.ok()) throw IoError("cannot register with the hub at " + d.options.hub_url + ": " + res.describe());
  d.refresh_allowed_origins();
}

void NodeServer::stop() {
  if (!impl_) return;
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

void NodeServer::wait() {
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::string NodeServer::url() const { return impl_->url(); }

}  // namespace meshflow::services
