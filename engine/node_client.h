#pragma once
// The engine's one way to reach nodes (DESIGN §2): run an atomic operation on the workflow's
// current mesh, or evaluate an analysis operation on it. Implementations keep the current
// mesh: in this process (InProcessNode, for `meshflow run`) or on HTTP nodes (the hub's jobs).

#include <cstdint>
#include <string>
#include <vector>

#include "services/operation.h"

namespace meshflow::engine {

struct StepReport {
  std::string operation;
  std::string node = "in-process";
  std::int64_t run_ms = 0;         // the operation itself, on the node
  std::int64_t wait_ms = 0;        // the node waiting for (or fetching) its input first
  std::int64_t transfer_ms = 0;    // later nodes fetching the result (the slowest of them)
  std::int64_t update_ms = 0;      // later nodes applying it (the slowest of them)
  std::string sent;                // "correction" or "output" ("" when no later node needed it)
  std::uint64_t correction_bytes = 0;
  std::uint64_t output_bytes = 0;
  std::uint64_t vertices = 0;     // atomic steps: of the output (0: unknown)
  bool is_analysis = false;
  double value = 0;               // analysis steps
};

class NodeClient {
 public:
  virtual ~NodeClient() = default;
  // Runs `operation` on the current mesh, which becomes its output.
  virtual StepReport run_atomic(const std::string& operation, const services::Params& params) = 0;
  // Evaluates an analysis operation on the current mesh.
  virtual StepReport run_analysis(const std::string& operation) = 0;
  // Before each step: the operations that may still run after it (from the executor's list of
  // active tasks), so that a step's result goes only to the nodes that will need it (DESIGN §6).
  virtual void expect_later(const std::vector<std::string>& operations) {}
};

}  // namespace meshflow::engine
