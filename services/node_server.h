#pragma once
// `meshflow node`: the HTTP interface of a mesh service (DESIGN §4), a thin binding over the
// operations of services/ and the download/update modules of protocol/. A node offers every
// operation of the registry, keeps meshes in its cache by SHA-256, and serves its outputs and
// corrections from /files with Range support. It registers with a hub using the node token
// and fetches only from the hub and the nodes the hub names.

#include <atomic>
#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace meshflow::services {

struct NodeOptions {
  std::string host = "127.0.0.1";
  int port = 0;                          // 0 picks a free port
  std::string advertise_url;             // how others reach us; default http://host:port
  std::filesystem::path data_dir;        // cache and files
  std::string hub_url;                   // register here when not empty
  std::string token;                     // the hub's node token
  std::uint64_t capacity_vertices = 50'000'000;  // largest mesh taken in memory
  int threads = 8;                       // HTTP worker threads
  std::vector<std::string> operations;   // the operations offered; empty: every one
  // A /run not finished within this answers 202 with a task URL to poll (DESIGN §4).
  std::chrono::milliseconds answer_within{std::chrono::seconds(20)};
};

class NodeServer {
 public:
  explicit NodeServer(NodeOptions options);
  ~NodeServer();
  NodeServer(const NodeServer&) = delete;
  NodeServer& operator=(const NodeServer&) = delete;

  // Binds and serves in a background thread; returns the bound port. \throws IoError.
  int start();
  // Registers with the hub (POST /api/services with the token). \throws IoError.
  void register_with_hub();
  void stop();
  void wait();  // until stop() (or a signal handler calling stop())
  std::string url() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace meshflow::services
