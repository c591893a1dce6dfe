#include "engine/in_process_node.h"

namespace meshflow::engine {
namespace {
std::int64_t ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::steady_clock::now() - start).count();
}
}  // namespace

InProcessNode::InProcessNode(mesh::Mesh input)
    : current_(std::move(input)), reference_diagonal_(mesh::bounding_box(current_).diagonal()) {}

StepReport InProcessNode::run_atomic(const std::string& operation, const services::Params& params) {
  auto start = std::chrono::steady_clock::now();
  services::RunContext context;
  context.reference_diagonal = reference_diagonal_;
  services::AtomicResult result = services::run_atomic(services::find_operation(operation), current_, params, context);
  current_ = std::move(result.output);
  StepReport report;
  report.operation = operation;
  report.run_ms = ms_since(start);
  return report;
}

StepReport InProcessNode::run_analysis(const std::string& operation) {
  auto start = std::chrono::steady_clock::now();
  StepReport report;
  report.operation = operation;
  report.is_analysis = true;
  report.value = services::run_analysis(services::find_operation(operation), current_);
  report.run_ms = ms_since(start);
  return report;
}

}  // namespace meshflow::engine
