#pragma once
// `meshflow hub`: the hub's HTTP server (DESIGN §1, §3): health and readiness, the operation
// list gathered from the registered nodes, node self-registration with the node token, and
// the job routes that run workflows on the nodes. The repository and the browser UI add their
// routes to the same server.

#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <optional>
#include <string>

namespace httplib {
class Server;
struct Request;
}

namespace meshflow::web {

struct HubOptions {
  std::string host = "127.0.0.1";
  int port = 0;                                // 0 picks a free port
  std::filesystem::path data_dir = "meshflow-data";
  bool allow_private_fetch = false;            // input_url on loopback/private ranges
  std::uint64_t max_upload_bytes = 8ull << 30; // meshes uploaded to /api/jobs
  int threads = 16;
  std::string public_url;                      // how nodes reach the hub; default http://host:port
  int max_loop_iterations = 100;               // bound on each while loop of a job
  std::string default_transfer = "smaller";    // jobs' default: "output" forces whole meshes
};

class HubServer {
 public:
  explicit HubServer(HubOptions options);
  ~HubServer();
  HubServer(const HubServer&) = delete;
  HubServer& operator=(const HubServer&) = delete;

  // Binds and serves in a background thread; returns the port. \throws IoError.
  int start();
  void stop();
  std::string url() const;
  std::filesystem::path token_file() const;  // DATA/node.token

  // /readyz answers 200 once every condition set here holds (store open, examples loaded,
  // the nodes `up` started registered...).
  void set_ready_condition(std::function<bool()> condition);
  bool is_ready() const;
  std::size_t registered_nodes() const;
  std::vector<std::string> offered_operations() const;  // by the registered nodes, now
  std::size_t registrations_since_start() const;  // node registrations since start()
  // Lets POST/DELETE /api/services by people too: `require` throws unless the request comes
  // from a curator (the accounts layer sets it); the node token is accepted as before.
  void set_service_curator_check(std::function<void(const httplib::Request&)> require);

  httplib::Server& http();  // for the layers that add routes

  // How POST /api/jobs turns a `workflow_id` into workflow XML (the repository sets it).
  void set_workflow_resolver(std::function<std::optional<std::string>(const std::string&)> resolver);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::web
