#pragma once
// Simplification of a large mesh in parts (DESIGN §9), every step out of core:
//   partition (parallel/partition.h) -> per-part step (services/part_simplify.h) on local
//   worker processes, threads or mesh nodes (parallel/node_dispatch.h), the parts taken in the
//   order of their independent sets -> seam pass and merge into one PLY (parallel/merge.h).
// Not the thesis's scheme (Rem files, boundary half-edge collapses): each part keeps its shared
// vertices fixed and a seam pass simplifies a band around the seams afterwards, with the
// parts' quadrics. That keeps the error within a few % of a single-node run, which the thesis
// scheme does not (its Table 9.3), and makes the parts independent: any order, any node count,
// the same result.

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "parallel/independent_sets.h"
#include "parallel/merge.h"
#include "parallel/partition.h"
#include "services/part_simplify.h"

namespace meshflow::parallel {

// Runs the per-part step on part p: DIR/part-<p>.mfp -> DIR/part-<p>.simplified.mfp.
using PartRunner = std::function<services::PartStats(std::size_t p, double max_error_abs)>;

struct DistributedParams {
  double max_error_percent = 0;  // of the input's diagonal, converted once here
  double max_error_abs = 0;      // when > 0, used as is instead (a workflow's own reference)
  std::size_t vertices_per_part = 1000000;
  unsigned workers = 2;          // parts at once (the nodes' count when dispatching to nodes)
  std::string parts_dir;
  // The per-part step: when empty, a process `worker_executable part-simplify DIR P
  // --max-error-abs X` if worker_executable is set, else a thread of this process.
  PartRunner runner;
  std::string worker_executable;
  std::function<void(const std::string& step, double fraction)> progress;
};

struct DistributedReport {
  PartitionInfo partition;
  std::vector<std::vector<std::uint32_t>> independent_sets;
  std::vector<services::PartStats> part_stats;
  MergeReport merge;
  double max_error_abs = 0, parts_seconds = 0;
  std::string to_json() const;
};

// The stats a part-simplify process or a node answered (zeros for what is missing).
services::PartStats stats_from_json(const nlohmann::json& stats);

// The per-part step in this process (a worker thread, or `meshflow part-simplify`).
services::PartStats simplify_one_part(const std::string& dir, std::size_t p, double max_error_abs);

// Every part, `params.workers` at a time, in the order of the independent sets.
void simplify_parts(const DistributedParams& params, DistributedReport& report);

// The three steps: IN -> OUT (canonical PLY; another extension is converted at the end).
DistributedReport simplify_distributed(const std::string& in, const std::string& out, const DistributedParams& params);

}  // namespace meshflow::parallel
