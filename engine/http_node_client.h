#pragma once
// The NodeClient of the hub's jobs: runs each step on an HTTP node and carries out the mesh
// transfer protocol (DESIGN §6, thesis §4.2): the input is broadcast to every node taking part
// before the first step; after each atomic step the correction or the whole output, whichever
// is smaller, goes to every other node taking part before the next step starts. A node that
// fails mid-step is left out and the step runs again on another node offering the operation.

#include <functional>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "engine/node_client.h"

namespace meshflow::engine {

struct HttpNodeOptions {
  std::string token;                 // the node token (nodes' mutating routes need it)
  std::vector<std::string> nodes;    // base URLs of the nodes taking part
  // Picks a node offering `operation`, none of `exclude` (least loaded first); empty: none left.
  std::function<std::optional<std::string>(const std::string& operation,
                                           const std::vector<std::string>& exclude)> pick;
  std::function<void(const std::string& node, int delta)> load;  // steps running on a node
  std::function<bool()> cancelled;
  double reference_diagonal = 0;     // of the workflow's input
};

class HttpNodeClient : public NodeClient {
 public:
  // The input mesh is at `input_url` (canonical PLY, zstd) with SHA-256 `input_sha256`.
  HttpNodeClient(HttpNodeOptions options, std::string input_url, std::string input_sha256);
  // Asks every node to download the input (one-way, in parallel on the nodes' side).
  void broadcast_input();
  StepReport run_atomic(const std::string& operation, const services::Params& params) override;
  StepReport run_analysis(const std::string& operation) override;
  const std::string& current_url() const { return current_url_; }
  // Resuming a job: the mesh after the last finished step is already on the nodes.
  void set_current(std::string url, std::string sha256) {
    current_url_ = std::move(url);
    current_sha_ = std::move(sha256);
  }
  const std::string& current_sha256() const { return current_sha_; }

 private:
  struct Answer;
  Answer run_on_some_node(const std::string& operation, const std::string& body);
  std::int64_t forward(const std::string& from_node, const std::string& base_sha, const Answer& answer,
                       StepReport& report);

  HttpNodeOptions options_;
  std::string current_url_, current_sha_;
  std::vector<std::string> dead_;
};

}  // namespace meshflow::engine
