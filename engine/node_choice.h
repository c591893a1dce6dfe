#pragma once
// Which node runs an operation (thesis §4.2: "locates the most appropriate servers"): among the
// nodes offering it, the least loaded (steps running there now plus the steps of this job
// already planned there, so a job's operations spread over equally good nodes as the thesis's
// services do), then the fastest measured link. A node not measured yet counts as fastest, so
// that it gets measured.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace meshflow::engine {

struct NodeCandidate {
  std::string url;
  int active_steps = 0;       // steps the hub runs on it now (all jobs)
  int planned_steps = 0;      // operations of the job being planned already placed on it
  double bandwidth_mbps = 0;  // measured from real transfers into it; 0: not measured yet
  std::uint64_t capacity_vertices = 0;  // the largest mesh it takes (/service.json); 0: not said
};

// \pre every candidate offers the operation. Returns nullopt when there is none.
std::optional<std::string> choose_node(const std::vector<NodeCandidate>& candidates);

// A node's bandwidth estimate after one more transfer of `bytes` in `ms` (an exponentially
// weighted mean in Mbit/s). Transfers shorter than kMinMeasuredBytes say more about latency
// than bandwidth and leave the estimate as it was.
constexpr std::uint64_t kMinMeasuredBytes = 64 * 1024;
double updated_bandwidth(double previous_mbps, std::uint64_t bytes, std::int64_t ms);

}  // namespace meshflow::engine
