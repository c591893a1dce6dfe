#pragma once
// Runs a validated workflow (thesis ch. 5): the engine keeps a list of active tasks, initially
// the workflow's body. It takes the first: an atomic task runs on a node; an `if` evaluates its
// condition (an analysis operation) and puts its body, or its else, in front of the list; a
// `while` evaluates its condition and, when true, puts a copy of its body followed by itself in
// front. A loop that comes round more than `max_loop_iterations` times stops the run.

#include <functional>

#include "engine/node_client.h"
#include "engine/validate.h"

namespace meshflow::engine {

struct ExecutorOptions {
  int max_loop_iterations = 100;
  std::function<void(const StepReport&)> on_step;  // after every step
  std::function<bool()> cancelled;                 // checked before every step
};

// \throws InvalidInput when a loop exceeds its bound (naming the loop's line), whatever the
// NodeClient throws when a step fails, std::runtime_error("cancelled").
void execute(const ValidatedWorkflow& workflow, NodeClient& nodes, const ExecutorOptions& options = {});

}  // namespace meshflow::engine
