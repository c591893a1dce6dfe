#pragma once
// The NodeClient of the hub's jobs: runs each step on an HTTP node and carries out the mesh
// transfer protocol (DESIGN §6, thesis §4.2). Before the first step it places every operation
// the workflow uses on a node (engine/node_choice.h) and has each node taking part download
// the input, along a binomial tree: the hub sends it to the node of the first step, then every
// node that has it passes it on to one more while the hub serves another, so the hub's link
// carries about log2(N + 1) copies instead of N, and the first step starts after one copy.
// After each atomic step it sends the correction or the whole output,
// whichever is smaller, to every node that runs a later operation, and starts the next step
// once they all have it. A node that fails mid-step is left out: its operations move to
// another node offering them and the step runs again there.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <functional>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "engine/node_choice.h"
#include "engine/node_client.h"

namespace meshflow::engine {

// What later nodes receive after an atomic step: the smaller of correction and output (the
// protocol), or always the whole output (to measure what the protocol saves).
enum class TransferMode { Smaller, Output };
const char* to_string(TransferMode mode);
// "smaller" or "output". \throws InvalidInput otherwise.
TransferMode transfer_mode_from_string(const std::string& text);

struct HttpNodeOptions {
  std::string token;  // the node token (nodes' mutating routes need it)
  // The registered nodes offering `operation`, with their load and measured bandwidth.
  std::function<std::vector<NodeCandidate>(const std::string& operation)> candidates;
  std::function<void(const std::string& node, int delta)> load;  // steps running on a node
  // A finished transfer into `node` (input, correction or output): bytes on the wire, ms.
  std::function<void(const std::string& node, std::uint64_t bytes, std::int64_t ms)> measured;
  std::function<void(const std::string& operation, const std::string& node)> on_start;
  std::function<bool()> cancelled;
  double reference_diagonal = 0;  // of the workflow's input
  TransferMode transfer = TransferMode::Smaller;
  // Large meshes (DESIGN §9): a Simplify step whose mesh has more vertices than every node
  // offering Simplify takes is split into parts simplified on those nodes (parallel/), here in
  // `work_dir`, and its output is served by the hub at the URL `publish` gives for a file there.
  std::uint64_t input_vertices = 0;  // of the workflow's input; 0: unknown (never split)
  std::string work_dir;
  std::function<std::string(const std::string& path)> publish;
  std::function<void(const std::string& step, double fraction)> progress;  // of a split step
};

// The input broadcast (thesis Table 4.3's IB): the slowest download of the input by a node.
struct BroadcastReport {
  std::int64_t ms = 0;
  std::uint64_t bytes = 0;  // of one copy
  std::vector<std::string> nodes;
};

class HttpNodeClient : public NodeClient {
 public:
  // The input mesh is at `input_url` (canonical PLY, zstd) with SHA-256 `input_sha256`.
  HttpNodeClient(HttpNodeOptions options, std::string input_url, std::string input_sha256);

  // Places each operation on a node. \throws IoError when no node offers one of them.
  void plan(const std::vector<std::string>& operations);
  // Starts the input broadcast in the background and returns at once (a node's /run waits for
  // its download).
  void broadcast();
  // Waits (bounded) until the broadcast is over: how long it took until every node had it.
  BroadcastReport broadcast_report();
  ~HttpNodeClient() override;

  StepReport run_atomic(const std::string& operation, const services::Params& params) override;
  StepReport run_analysis(const std::string& operation) override;
  void expect_later(const std::vector<std::string>& operations) override { later_ = operations; }

  const std::string& current_url() const { return current_url_; }
  const std::string& current_sha256() const { return current_sha_; }
  // The node that produced the current mesh ("" while it is the input).
  const std::string& current_node() const { return current_node_; }
  // Resuming a job: the mesh after the last finished step, with `vertices` vertices (0:
  // unknown), is already on the nodes.
  void set_current(std::string url, std::string sha256, std::string node, std::uint64_t vertices) {
    current_url_ = std::move(url);
    current_sha_ = std::move(sha256);
    current_node_ = std::move(node);
    current_vertices_ = vertices;
  }
  std::vector<std::string> nodes_taking_part() const;
  const std::map<std::string, std::string>& placement() const { return plan_; }

 private:
  struct Answer;
  std::string place(const std::string& operation);
  Answer run_on_some_node(const std::string& operation, const std::string& body);
  void forward(const std::string& from_node, const std::string& base_sha, const Answer& answer,
               StepReport& report);
  bool is_dead(const std::string& node) const;
  void run_broadcast(std::vector<std::string> targets);
  void wait_until_told(const std::string& node);  // its input download has been asked for
  // The Simplify nodes, when the current mesh is larger than each of them takes; else empty.
  std::vector<NodeCandidate> nodes_too_small_for(const std::string& operation) const;
  StepReport run_split(const std::vector<NodeCandidate>& nodes, const services::Params& params);

  HttpNodeOptions options_;
  std::string input_url_, input_sha_;
  // The broadcast, in its own thread.
  std::thread broadcaster_;
  std::atomic<bool> stop_broadcast_{false};
  std::mutex broadcast_mutex_;
  std::condition_variable broadcast_changed_;
  std::vector<std::string> to_tell_;  // nodes whose download is not asked for yet
  BroadcastReport broadcast_;
  std::string current_url_, current_sha_, current_node_;
  std::map<std::string, std::string> plan_;  // operation -> node
  std::vector<std::string> later_;
  std::vector<std::string> dead_;
  std::uint64_t current_vertices_ = 0;  // 0: unknown
  int splits_ = 0;
};

}  // namespace meshflow::engine
