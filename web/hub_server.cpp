#include "web/hub_server.h"

#include <httplib.h>

#include <chrono>
#include <fstream>
#include <map>
#include <nlohmann/json.hpp>
#include <thread>

#include "mesh/errors.h"
#include "protocol/http_server.h"
#include "repository/accounts.h"
#include "web/job_manager.h"
#include "web/service_registry.h"

namespace meshflow::web {
namespace {

using nlohmann::json;

// The node token: made on first start, kept in DATA/node.token (mode 0600).
std::string load_or_create_token(const std::filesystem::path& file) {
  std::ifstream in(file);
  std::string token;
  if (in && std::getline(in, token) && token.size() >= 32) return token;
  token = repository::random_hex(32);
  std::filesystem::path tmp = file;
  tmp += ".tmp";
  {
    std::ofstream out(tmp);
    out << token << "\n";
    if (!out) throw IoError("cannot write " + tmp.string());
  }
  std::filesystem::permissions(tmp, std::filesystem::perms::owner_read |
                                        std::filesystem::perms::owner_write);
  std::filesystem::rename(tmp, file);
  return token;
}

std::string bearer(const httplib::Request& req) {
  std::string header = req.get_header_value("Authorization");
  const std::string prefix = "Bearer ";
  return header.rfind(prefix, 0) == 0 ? header.substr(prefix.size()) : std::string();
}

}  // namespace

struct HubServer::Impl {
  HubOptions options;
  httplib::Server server;
  std::thread thread;
  int port = 0;
  std::string token;
  std::unique_ptr<ServiceRegistry> services;
  std::unique_ptr<JobManager> jobs;
  std::function<bool()> ready_condition;
  std::function<std::optional<std::string>(const std::string&)> workflow_resolver;
  std::atomic<std::uint64_t> requests{0};
  std::atomic<std::size_t> registrations{0};  // since this start
  std::function<void(const httplib::Request&)> service_curator_check;

  std::string url() const {
    return options.public_url.empty() ? "http://" + options.host + ":" + std::to_string(port)
                                      : options.public_url;
  }

  void routes() {
    protocol::install_error_handling(server);
    server.set_logger([this](const httplib::Request&, const httplib::Response&) { requests++; });
    server.Get("/healthz", [](const httplib::Request&, httplib::Response& res) {
      res.set_content(R"({"status":"ok"})", "application/json");
    });
    server.Get("/readyz", [this](const httplib::Request&, httplib::Response& res) {
      bool ready = !ready_condition || ready_condition();
      res.status = ready ? 200 : 503;
      res.set_content(json{{"ready", ready}, {"nodes", services->list().size()}}.dump(),
                      "application/json");
    });
    server.Get("/metrics", [this](const httplib::Request&, httplib::Response& res) {
      std::string text = "# TYPE meshflow_http_requests_total counter\nmeshflow_http_requests_total " +
                         std::to_string(requests.load()) +
                         "\n# TYPE meshflow_registered_nodes gauge\nmeshflow_registered_nodes " +
                         std::to_string(services->list().size()) + "\n";
      res.set_content(text, "text/plain; version=0.0.4");
    });
    server.Get("/api/operations", [this](const httplib::Request&, httplib::Response& res) {
      res.set_content(json{{"operations", services->operations()}}.dump(), "application/json");
    });
    server.Get("/api/services", [this](const httplib::Request&, httplib::Response& res) {
      json list = json::array();
      for (const auto& s : services->list())
        list.push_back({{"url", s.url},
                        {"capacity_vertices", s.capacity_vertices},
                        {"active_steps", s.active_steps},
                        {"bandwidth_mbps", s.bandwidth_mbps},
                        {"operations", s.service.value("operations", json::array()).size()},
                        {"version", s.service.value("version", "")}});
      res.set_content(json{{"services", list}}.dump(), "application/json");
    });
    // Nodes register themselves with the node token; curators register by URL (accounts
    // arrive with the repository issue: until then only the node token may register).
    server.Post("/api/services", [this](const httplib::Request& req, httplib::Response& res) {
      require_node_or_curator(req, "registering a node");
      json body = json::parse(req.body, nullptr, false);
      if (!body.is_object() || !body.contains("url") || !body["url"].is_string())
        throw InvalidInput("expected {\"url\": \"http://node:port\"}");
      ServiceInfo info = services->add(body["url"].get<std::string>());
      registrations++;
      res.status = 201;
      json names = json::array();
      for (const auto& op : info.service["operations"]) names.push_back(op.value("name", ""));
      res.set_content(json{{"url", info.url}, {"operations", names.size()}, {"operation_names", names}}.dump(),
                      "application/json");
    });
    job_routes();
    server.Delete("/api/services", [this](const httplib::Request& req, httplib::Response& res) {
      require_node_or_curator(req, "removing a node");
      std::string url = req.get_param_value("url");
      if (!services->remove(url)) throw protocol::NotFound("no registered node " + url);
      res.status = 204;
    });
  }

  // The node token, or a curator's session/API token once the accounts layer is plugged in.
  void require_node_or_curator(const httplib::Request& req, const std::string& what) {
    if (!token.empty() && bearer(req) == token) return;
    if (!service_curator_check) throw protocol::Unauthorized(what + " needs the node token");
    service_curator_check(req);
  }

  // POST /api/jobs: multipart fields `workflow` (XML) and `input` (the mesh, streamed to disk)
  // or `input_url` (fetched by the hub), optional `transfer` ("output": always the whole mesh).
  void job_routes() {
    constexpr std::size_t kMaxField = 4 << 20;
    server.Post("/api/jobs", [this](const httplib::Request& req, httplib::Response& res,
                                    const httplib::ContentReader& reader) {
      if (!req.is_multipart_form_data())
        throw InvalidInput("POST /api/jobs wants multipart/form-data with fields 'workflow' and 'input' or 'input_url'");
      std::string id = jobs->new_id();
      std::filesystem::path dir = jobs->job_dir(id);
      std::filesystem::create_directories(dir);
      std::filesystem::path upload = dir / "upload";
      std::map<std::string, std::string> fields;
      std::ofstream file;
      std::string field;
      bool too_big = false;
      std::uint64_t upload_bytes = 0;
      bool ok = reader(
          [&](const httplib::MultipartFormData& part) {
            if (file.is_open()) file.close();
            field = part.name;
            if (field == "input") file.open(upload, std::ios::binary);
            return true;
          },
          [&](const char* data, std::size_t length) {
            if (field == "input") {
              file.write(data, static_cast<std::streamsize>(length));
              upload_bytes += length;
              return static_cast<bool>(file);
            }
            std::string& value = fields[field];
            if (value.size() + length > kMaxField) {
              too_big = true;
              return false;
            }
            value.append(data, length);
            return true;
          });
      if (file.is_open()) file.close();
      auto discard = [&] {
        std::error_code ignored;
        std::filesystem::remove_all(dir, ignored);
      };
      if (too_big) {
        discard();
        throw LimitExceeded("a form field of POST /api/jobs is too large", kMaxField, kMaxField + 1);
      }
      if (!ok) {
        discard();
        throw InvalidInput("the upload was cut short or exceeds the limit");
      }
      if (!fields.count("workflow") && fields.count("workflow_id") && workflow_resolver) {
        auto xml = workflow_resolver(fields["workflow_id"]);
        if (!xml) {
          discard();
          throw protocol::NotFound("no workflow " + fields["workflow_id"] + " in the repository");
        }
        fields["workflow"] = *xml;
      }
      if (!fields.count("workflow")) {
        discard();
        throw InvalidInput("missing the 'workflow' field (the workflow XML)");
      }
      JobRequest request;
      request.id = id;
      request.workflow_xml = fields["workflow"];
      if (fields.count("workflow_id")) request.workflow_id = fields["workflow_id"];
      if (upload_bytes > 0) request.upload = upload;
      else std::filesystem::remove(upload);
      request.input_url = fields["input_url"];
      if (fields.count("transfer")) request.transfer = fields["transfer"];
      if (upload_bytes > 0 && !request.input_url.empty()) {
        discard();
        throw InvalidInput("give either 'input' (a mesh file) or 'input_url', not both");
      }
      try {
        jobs->submit(request);
      } catch (...) {
        discard();
        throw;
      }
      res.status = 202;
      res.set_content(json{{"id", id}, {"state", "queued"}}.dump(), "application/json");
    });
    server.Get(R"(/api/jobs/([0-9a-f]+))", [this](const httplib::Request& req, httplib::Response& res) {
      auto status = jobs->status(req.matches[1]);
      if (!status) throw protocol::NotFound("no job " + std::string(req.matches[1]));
      res.set_content(status->dump(), "application/json");
    });
    server.Delete(R"(/api/jobs/([0-9a-f]+))", [this](const httplib::Request& req, httplib::Response& res) {
      if (!jobs->cancel(req.matches[1])) throw protocol::NotFound("no job " + std::string(req.matches[1]));
      res.status = 202;
      res.set_content(R"({"state":"cancelling"})", "application/json");
    });
    server.Get(R"(/api/jobs/([0-9a-f]+)/input)", [this](const httplib::Request& req, httplib::Response& res) {
      protocol::serve_file(req, res, jobs->input_file(req.matches[1]).string(), "application/zstd");
    });
    // The output of a Simplify step run in parts (engine/http_node_client.h), for later nodes.
    server.Get(R"(/api/jobs/([0-9a-f]+)/split/(split-[0-9]+)/output\.ply\.zst)",
               [this](const httplib::Request& req, httplib::Response& res) {
                 auto file = jobs->job_dir(req.matches[1]) / "split" / std::string(req.matches[2]) / "output.ply.zst";
                 if (!std::filesystem::exists(file)) throw protocol::NotFound("no such split output");
                 protocol::serve_file(req, res, file.string(), "application/zstd");
               });
    server.Get(R"(/api/jobs/([0-9a-f]+)/output)", [this](const httplib::Request& req, httplib::Response& res) {
      auto status = jobs->status(req.matches[1]);
      if (!status) throw protocol::NotFound("no job " + std::string(req.matches[1]));
      if ((*status)["state"] != "done")
        throw protocol::NotFound("job " + std::string(req.matches[1]) + " has no output (state " +
                                 (*status)["state"].get<std::string>() + ")");
      res.set_header("Content-Disposition", "attachment; filename=\"" + std::string(req.matches[1]) + ".ply\"");
      protocol::serve_file(req, res, jobs->output_file(req.matches[1]).string(), "application/octet-stream");
    });
    // Server-Sent Events: the job's status whenever it changes, until it ends.
    server.Get(R"(/api/jobs/([0-9a-f]+)/events)", [this](const httplib::Request& req, httplib::Response& res) {
      std::string id = req.matches[1];
      if (!jobs->status(id)) throw protocol::NotFound("no job " + id);
      res.set_header("Cache-Control", "no-cache");
      auto last = std::make_shared<std::string>();
      res.set_chunked_content_provider("text/event-stream", [this, id, last](std::size_t, httplib::DataSink& sink) {
        for (int i = 0; i < 40; ++i) {
          auto status = jobs->status(id);
          std::string text = status ? status->dump() : "{}";
          if (text != *last) {
            *last = text;
            std::string event = "data: " + text + "\n\n";
            if (!sink.write(event.data(), event.size())) return false;
            std::string state = status ? (*status)["state"].get<std::string>() : "failed";
            if (state == "done" || state == "failed" || state == "cancelled") {
              sink.done();
              return true;
            }
          }
          std::this_thread::sleep_for(std::chrono::milliseconds(250));
        }
        return sink.write(": keep-alive\n\n", 15);
      });
    });
  }
};

HubServer::HubServer(HubOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
  std::filesystem::create_directories(impl_->options.data_dir);
  impl_->token = load_or_create_token(token_file());
  impl_->services = std::make_unique<ServiceRegistry>(impl_->options.data_dir / "services.json");
  impl_->jobs = std::make_unique<JobManager>(impl_->options.data_dir, *impl_->services, impl_->token);
  int threads = impl_->options.threads;
  impl_->server.new_task_queue = [threads] { return new httplib::ThreadPool(threads); };
  impl_->server.set_payload_max_length(impl_->options.max_upload_bytes);
  impl_->routes();
}

HubServer::~HubServer() { stop(); }

int HubServer::start() {
  Impl& d = *impl_;
  d.port = d.options.port == 0 ? d.server.bind_to_any_port(d.options.host)
                               : (d.server.bind_to_port(d.options.host, d.options.port)
                                      ? d.options.port
                                      : -1);
  if (d.port <= 0)
    throw IoError("cannot listen on " + d.options.host + ":" + std::to_string(d.options.port));
  d.jobs->set_fetch_policy(d.options.allow_private_fetch, d.options.max_upload_bytes);
  d.jobs->set_max_loop_iterations(d.options.max_loop_iterations);
  d.jobs->set_default_transfer(d.options.default_transfer);
  d.jobs->start(d.url());
  d.thread = std::thread([&d] { d.server.listen_after_bind(); });
  d.services->prune_unreachable();
  return d.port;
}

void HubServer::stop() {
  if (!impl_) return;
  impl_->server.stop();
  if (impl_->thread.joinable()) impl_->thread.join();
}

std::string HubServer::url() const { return impl_->url(); }
std::filesystem::path HubServer::token_file() const { return impl_->options.data_dir / "node.token"; }
void HubServer::set_workflow_resolver(
    std::function<std::optional<std::string>(const std::string&)> resolver) {
  impl_->workflow_resolver = std::move(resolver);
}
void HubServer::set_ready_condition(std::function<bool()> condition) {
  impl_->ready_condition = std::move(condition);
}
bool HubServer::is_ready() const { return !impl_->ready_condition || impl_->ready_condition(); }
std::size_t HubServer::registered_nodes() const { return impl_->services->list().size(); }
std::vector<std::string> HubServer::offered_operations() const {
  return impl_->services->offered_operations();
}
std::size_t HubServer::registrations_since_start() const { return impl_->registrations; }
httplib::Server& HubServer::http() { return impl_->server; }
void HubServer::set_service_curator_check(std::function<void(const httplib::Request&)> require) {
  impl_->service_curator_check = std::move(require);
}

}  // namespace meshflow::web
