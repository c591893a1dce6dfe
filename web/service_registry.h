#pragma once
// The nodes registered with the hub: base URL, the operations each offers (from its
// /service.json), capacity, and live load. Persisted as DATA/services.json so a restarted hub
// knows its nodes. (The repository issue also states services as RDF.)

#include <cstdint>
#include <filesystem>
#include <mutex>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "engine/node_choice.h"

namespace meshflow::web {

struct ServiceInfo {
  std::string url;
  nlohmann::json service;              // the node's /service.json
  std::uint64_t capacity_vertices = 0;
  double bandwidth_mbps = 0;           // measured from real transfers into it (0: not yet)
  int active_steps = 0;                // steps the hub is running on it now
  bool offers(const std::string& operation) const;
};

class ServiceRegistry {
 public:
  explicit ServiceRegistry(std::filesystem::path file);

  // Reads the node's /service.json and adds (or refreshes) it. \throws IoError when the node
  // does not answer, InvalidInput when its answer is not a service description.
  ServiceInfo add(const std::string& url);
  bool remove(const std::string& url);
  // Drops the nodes that do not answer /service.json (nodes of an earlier run, gone).
  void prune_unreachable();
  std::vector<ServiceInfo> list() const;
  std::optional<ServiceInfo> find(const std::string& url) const;

  // The node to run `operation` on: offers it, not excluded, least loaded, then fastest
  // (engine/node_choice.h).
  std::optional<std::string> choose(const std::string& operation,
                                    const std::vector<std::string>& exclude = {}) const;
  // The nodes offering `operation`, with their load and measured bandwidth.
  std::vector<engine::NodeCandidate> candidates(const std::string& operation) const;
  void adjust_load(const std::string& url, int delta);
  // A transfer of `bytes` into the node took `ms`: refines its bandwidth estimate.
  void record_transfer(const std::string& url, std::uint64_t bytes, std::int64_t ms);

  // Every operation offered by some node (first description wins), for /api/operations.
  nlohmann::json operations() const;
  // The names of the operations the registered nodes offer now (for runnable=true).
  std::vector<std::string> offered_operations() const;

 private:
  void save() const;
  std::filesystem::path file_;
  mutable std::mutex mutex_;
  std::vector<ServiceInfo> services_;
};

}  // namespace meshflow::web
