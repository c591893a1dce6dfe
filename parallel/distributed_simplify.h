#pragma once
// Simplification of a large mesh in parts (DESIGN §9), every step out of core:
//   partition (parallel/partition.h) -> per-part step (services/part_simplify.h) on local
//   worker processes, threads or mesh nodes (parallel/node_dispatch.h), the parts taken in the
//   order of their independent sets -> seam pass and merge into one PLY (parallel/merge.h).
// Local workers follow the thesis's scheme (Rem files, ch. 9): parts go in the order of their
// independent sets, a part starting once its earlier neighbours are done; each replays what its
// simplified neighbours removed on their common boundaries (DIR/rem-<from>-<to>.bin), keeps the
// vertices shared by 3+ parts or with a simplified neighbour, half-edge-collapses along its
// boundaries with later neighbours and writes what it removed there for them. The seam pass
// then simplifies a band around what stayed fixed (mostly near 3+ vertices). The order does
// not depend on the worker count, so neither does the result. Nodes (a PartRunner, parallel/
// node_dispatch.h) follow the same scheme with the Rem files carried over HTTP.

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

// Runs the per-part step on part p as simplify_one_part does (DIR/part-<p>.mfp and the Rem files
// for p -> p's Rem files, then DIR/part-<p>.simplified.mfp), elsewhere.
using PartRunner = std::function<services::PartStats(std::size_t p, double max_error_abs, bool fixed_seams)>;

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
  bool fixed_seams = false;  // keep every shared vertex fixed (no Rem files; the seam pass does the seams)
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

// The per-part step in this process (a worker thread, or `meshflow part-simplify`), Rem scheme:
// reads DIR/partition.txt and the Rem files for p, writes p's Rem files then its simplified part.
// With fixed_seams: every shared vertex fixed, no Rem file read or written.
services::PartStats simplify_one_part(const std::string& dir, std::size_t p, double max_error_abs, bool fixed_seams = false);

// Every part, `params.workers` at a time, in the order of the independent sets (Rem files of an
// earlier run in the directory are removed first).
void simplify_parts(const DistributedParams& params, DistributedReport& report);

// The three steps: IN -> OUT (canonical PLY; another extension is converted at the end).
DistributedReport simplify_distributed(const std::string& in, const std::string& out, const DistributedParams& params);

}  // namespace meshflow::parallel
