#pragma once
// Runs a workflow through a hub's job routes (DESIGN §3), as `meshflow run --hub URL` does:
// submits the workflow and the input mesh (multipart upload), follows the job's steps until
// it ends, cancels it on the hub when interrupted, and downloads the result.

#include <chrono>
#include <functional>
#include <string>

#include "engine/node_client.h"

namespace meshflow::engine {

struct RemoteJobOptions {
  std::string transfer = "smaller";  // or "output": whole meshes between nodes (comparisons)
  std::function<void(const StepReport&)> on_step;  // each step once it has finished
  std::function<void(const std::string& job_url)> on_submitted;
  std::function<bool()> interrupted;                // polled; true: cancel the job and stop
  std::chrono::milliseconds poll_every{100};
};

struct RemoteJobResult {
  std::string id;
  std::string output_sha256;  // of the canonical PLY
  std::int64_t elapsed_ms = 0;
};

// \throws InvalidInput when the hub refuses the job (its message: file, line, column, reason),
// IoError when the hub cannot be reached, the job fails or the output does not arrive whole,
// std::runtime_error("cancelled") when interrupted (the job is cancelled on the hub first).
RemoteJobResult run_on_hub(const std::string& hub_url, const std::string& workflow_path,
                           const std::string& input_path, const std::string& output_path,
                           const RemoteJobOptions& options = {});

}  // namespace meshflow::engine
