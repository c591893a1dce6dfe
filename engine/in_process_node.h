#pragma once
// A NodeClient that runs the operations of services/ in this process (`meshflow run`).

#include <chrono>

#include "engine/node_client.h"
#include "mesh/mesh.h"

namespace meshflow::engine {

class InProcessNode : public NodeClient {
 public:
  // Distances in parameters are % of the diagonal of `input` (the workflow's input).
  explicit InProcessNode(mesh::Mesh input);
  StepReport run_atomic(const std::string& operation, const services::Params& params) override;
  StepReport run_analysis(const std::string& operation) override;
  const mesh::Mesh& current() const { return current_; }

 private:
  mesh::Mesh current_;
  double reference_diagonal_;
};

}  // namespace meshflow::engine
